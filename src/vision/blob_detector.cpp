#include "vision/blob_detector.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <span>
#include <type_traits>

#include <opencv2/core/hal/intrin.hpp>

#include "core/geometry.hpp"
#include "vision/marker_family.hpp"

namespace rilbed::vision {

namespace {
// Fraction of the marker's outer diameter taken by the dark disc the detector finds.
constexpr double kDiscFraction = MarkerFamily::black_ring_outer_radius;
// Pixels are sampled every kStatStep rows for the tile statistics (every column): the
// thinnest feature they must see (a 24 px marker's black ring) is over 2 px wide.
constexpr int kStatStep = 2;
// The statistics pass asks for the rows it samples of the tile row this many rows
// ahead, and the mask pass for all rows of the next tile row's tiles with contrast
// (the rows the statistics skipped), towards L2. A frame from a camera is in no cache,
// and the hardware's own prefetcher stops at every 4 KiB page (three rows of a
// 1280-pixel frame): without the hints a 64-marker search took a quarter longer on a
// frame flushed from the caches than on one left in L3 by an earlier pass.
// Two tile rows ahead leaves the memory time to answer; one was too close.
constexpr int kPrefetchTileRows = 2;
// Zero bytes kept on each side of every row of the dark mask.
constexpr int kMaskPad = 16;
// Dark-mask bits: below the threshold (filled), and well below it (may seed a fill).
constexpr std::uint8_t kDarkBit = 1, kDeepBit = 2;
// Least dark fraction of a swept region for the sweep to stand: a marker's black ring
// is half its dark disc's area, and its hole and two black guard slices add more.
constexpr double kMinDarkFraction = 0.5;

// The grey level below which a pixel may seed a fill: a quarter of the neighbourhood's
// range below the threshold (a quarter above its darkest pixel), where a marker's black
// always lies and the floor's mottling just under the threshold does not. With a fixed
// threshold (a tracked search) there is no range: every dark pixel may seed.
std::uint8_t deep_threshold(std::uint8_t threshold, std::uint8_t range, bool local_thresholds) {
  if (!local_thresholds) return threshold;
  return static_cast<std::uint8_t>(std::max(1, threshold - range / 4));
}
}  // namespace

// The kernels below are written once with OpenCV's universal intrinsics (SSE2 on x86,
// NEON on ARM, OpenCV's C++ emulation elsewhere), sixteen bytes per vector.
namespace {
using cv::v_float64x2;
using cv::v_uint16x8;
using cv::v_uint8x16;

// Sixteen bytes from any address.
v_uint8x16 load16(const std::uint8_t* p) { return cv::v_load(p); }

// Bit i set where byte i of `v` is nonzero.
unsigned nonzero_bits(const v_uint8x16& v) {
  return static_cast<unsigned>(cv::v_signmask(v == cv::v_setzero_u8())) ^ 0xFFFFu;
}
unsigned nonzero_bits(const std::uint8_t* p) { return nonzero_bits(load16(p)); }

// Each eight-byte half of `v` folded by `op` (min or max) onto its first byte: three
// shifts of the two 64-bit lanes, which move bytes towards the first on a little-endian CPU.
static_assert(std::endian::native == std::endian::little, "fold_halves and store_half_results read bytes as lane bits");
template <class Op>
v_uint8x16 fold_halves(v_uint8x16 v, Op op) {
  v = op(v, cv::v_reinterpret_as_u8(cv::v_shr<32>(cv::v_reinterpret_as_u64(v))));
  v = op(v, cv::v_reinterpret_as_u8(cv::v_shr<16>(cv::v_reinterpret_as_u64(v))));
  return op(v, cv::v_reinterpret_as_u8(cv::v_shr<8>(cv::v_reinterpret_as_u64(v))));
}

// The first byte of each eight-byte half into out[0] and out[1], as the low bytes of
// 16-bit lanes 0 and 4: one instruction each on SSE2 and NEON (a byte extract needs
// SSE4.1 or a shift first).
void store_half_results(const v_uint8x16& v, std::uint8_t* out) {
  const v_uint16x8 lanes = cv::v_reinterpret_as_u16(v);
  out[0] = static_cast<std::uint8_t>(cv::v_extract_n<0>(lanes));
  out[1] = static_cast<std::uint8_t>(cv::v_extract_n<4>(lanes));
}

// Neighbouring bytes of `a` and then of `b` folded in pairs by `op` (min or max): byte i
// of the result is op(a[2i], a[2i+1]) for i < 8 and op(b[2i-16], b[2i-15]) after. Each
// 16-bit lane's high byte is shifted onto its low byte and folded there, in bytes (SSE2
// has no 16-bit unsigned min or max); the low bytes, as non-negative 16-bit lanes, are
// then packed with unsigned saturation, which leaves them exact (one instruction on SSE2
// and on NEON).
template <class Op>
CV_ALWAYS_INLINE v_uint8x16 fold_pairs(const v_uint8x16& a, const v_uint8x16& b, Op op) {
  const cv::v_int16x8 low = cv::v_setall_s16(0x00FF);
  auto fold = [&](const v_uint8x16& v) {
    const v_uint8x16 high_down = cv::v_reinterpret_as_u8(cv::v_shr<8>(cv::v_reinterpret_as_u16(v)));
    return cv::v_reinterpret_as_s16(op(v, high_down)) & low;
  };
  return cv::v_pack_u(fold(a), fold(b));
}

// Sixteen eight-byte groups (eight vectors, in order) folded by `op` into one vector,
// byte i holding group i's result: three rounds of fold_pairs, each halving the vectors
// and doubling the bytes each result byte covers. About three operations a group, where
// folding each vector's halves on its own took seven and two byte extracts.
template <class Op>
CV_ALWAYS_INLINE v_uint8x16 fold_groups_of_eight(const std::array<v_uint8x16, 8>& v, Op op) {
  const v_uint8x16 q0 = fold_pairs(v[0], v[1], op), q1 = fold_pairs(v[2], v[3], op);
  const v_uint8x16 q2 = fold_pairs(v[4], v[5], op), q3 = fold_pairs(v[6], v[7], op);
  return fold_pairs(fold_pairs(q0, q1, op), fold_pairs(q2, q3, op), op);
}

// Zeroes mask bytes [a, b] of a row with kMaskPad bytes after it. A textured floor's
// regions are mostly runs of a few pixels, and a call of memset per run cost more than
// the fill's own work: a span of up to sixteen bytes is one load, a mask and one store
// (the bytes after it written back as they were).
void clear_span(std::uint8_t* row, int a, int b) {
  const int length = b - a + 1;
  if (length <= 0) return;
  if (length > 16) {
    std::memset(row + a, 0, static_cast<std::size_t>(length));
    return;
  }
  // keep[i] is 0xFF for i >= 16 (so that keep + 16 - length is `length` zeros, then ones).
  static constexpr std::array<std::uint8_t, 32> keep = {
      0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,
      0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
  cv::v_store(row + a, load16(row + a) & load16(keep.data() + 16 - length));
}
}  // namespace

const char* rejection_name(RegionRejection why) {
  switch (why) {
    case RegionRejection::kCut: return "cut";
    case RegionRejection::kTooSmall: return "too small";
    case RegionRejection::kNotCompact: return "not compact";
    case RegionRejection::kDimOutline: return "dim outline";
    case RegionRejection::kDegenerate: return "degenerate";
    case RegionRejection::kElongated: return "elongated";
    case RegionRejection::kAreaMismatch: return "area mismatch";
    case RegionRejection::kRaggedOutline: return "ragged outline";
  }
  return "?";
}

double Blob::disc_diameter_px() const { return 2.0 * std::sqrt(filled_area_px / kPi); }

int rays_crossing_bright(const cv::Mat& grey, const Blob& blob, int rays, double from, double to) {
  CV_Assert(grey.type() == CV_8UC1);
  // Each ray's direction in pixels: the shape maps the unit circle to the outline.
  std::vector<cv::Point2d> directions(static_cast<std::size_t>(rays));
  for (int k = 0; k < rays; ++k) {
    const double a = 2.0 * kPi * k / rays;
    directions[static_cast<std::size_t>(k)] = {blob.shape(0, 0) * std::cos(a) + blob.shape(0, 1) * std::sin(a),
                                               blob.shape(1, 0) * std::cos(a) + blob.shape(1, 1) * std::sin(a)};
  }
  auto grey_at = [&](const cv::Point2d& d, double r, int& out) {
    const int x = static_cast<int>(std::lround(blob.u + r * d.x));
    const int y = static_cast<int>(std::lround(blob.v + r * d.y));
    if (x < 0 || y < 0 || x >= grey.cols || y >= grey.rows) return false;
    out = grey.at<std::uint8_t>(y, x);
    return true;
  };
  // The blob's own contrast: halfway between its rim (0.9 of its radius) and what lies
  // just outside it (1.25). The local threshold at its centre does not serve: a dark
  // region wider than the tiles' neighbourhood has no contrast at its centre.
  double rim = 0, outside = 0;
  int rim_n = 0, outside_n = 0;
  for (const cv::Point2d& d : directions) {
    int g = 0;
    if (grey_at(d, 0.9, g)) rim += g, ++rim_n;
    if (grey_at(d, 1.25, g)) outside += g, ++outside_n;
  }
  if (rim_n == 0 || outside_n == 0) return 0;
  const double threshold = 0.5 * (rim / rim_n + outside / outside_n);
  int crossing = 0;
  for (const cv::Point2d& d : directions) {
    const double length_px = std::hypot(d.x, d.y);
    if (length_px <= 0) continue;
    const double step = 0.5 / length_px;  // half a pixel, as a fraction of the radius
    for (double r = from; r <= to; r += step) {
      int g = 0;
      if (!grey_at(d, r, g)) break;
      if (g > threshold) {
        ++crossing;
        break;
      }
    }
  }
  return crossing;
}

// Bookkeeping of one region (swept or filled).
struct BlobDetector::Fill {
  int area = 0;                        // dark pixels in the region
  int extent_area = 0;                 // pixels within its row extents (a sweep's; the fill leaves 0)
  int x0 = 0, x1 = 0, y0 = 0, y1 = 0;  // bounding box, inclusive
  bool touches_border = false;
  bool too_large = false;
};

BlobDetector::BlobDetector(BlobDetectorConfig config) { set_config(config); }

void BlobDetector::set_config(BlobDetectorConfig config) {
  config.tile_px = std::max(2, config.tile_px);
  config.min_diameter_px = std::max(6.0, config.min_diameter_px);
  if (config.tile_px != config_.tile_px) size_ = cv::Size();  // the tiles are laid out again
  config_ = config;
}

void BlobDetector::prepare(const cv::Mat& grey) {
  if (grey.size() == size_) return;
  size_ = grey.size();
  tiles_x_ = (size_.width + config_.tile_px - 1) / config_.tile_px;
  tiles_y_ = (size_.height + config_.tile_px - 1) / config_.tile_px;
  tile_col_.resize(size_.width);
  tile_row_.resize(size_.height);
  for (int x = 0; x < size_.width; ++x) tile_col_[x] = x / config_.tile_px;
  for (int y = 0; y < size_.height; ++y) tile_row_[y] = y / config_.tile_px;
  const std::size_t tiles = static_cast<std::size_t>(tiles_x_) * tiles_y_;
  tile_min_.assign(tiles, 0);
  tile_max_.assign(tiles, 0);
  tile_threshold_.assign(tiles, 0);
  row_min_scratch_.assign(tiles, 0);
  tile_range_.assign(tiles, 0);
  contrast_tiles_.assign(tiles, 0);
  contrast_tile_count_.assign(tiles_y_, 0);
  row_max_scratch_.assign(tiles, 0);
  // Sixteen zero bytes beside every row, so that sixteen-byte loads around any pixel of
  // a row stay in the buffer and read "not dark" outside the image.
  dark_storage_ = cv::Mat::zeros(size_.height, size_.width + 2 * kMaskPad, CV_8UC1);
  dark_ = dark_storage_(cv::Rect(kMaskPad, 0, size_.width, size_.height));
  dark_written_.assign(tiles, 0);
  row_min_x_.assign(size_.height, 0);
  row_max_x_.assign(size_.height, -1);
  row_stamp_.assign(size_.height, 0);
  col_min_y_.assign(size_.width, 0);
  col_max_y_.assign(size_.width, -1);
}

void BlobDetector::compute_thresholds(const cv::Mat& grey, cv::Rect roi) {
  const int t = config_.tile_px;
  const int tx0 = std::max(0, roi.x / t - 1), tx1 = std::min(tiles_x_ - 1, (roi.x + roi.width - 1) / t + 1);
  const int ty0 = std::max(0, roi.y / t - 1), ty1 = std::min(tiles_y_ - 1, (roi.y + roi.height - 1) / t + 1);
  for (int ty = ty0; ty <= ty1; ++ty) {
    const int y_end = std::min(size_.height, (ty + 1) * t);
    prefetch_sampled_rows(grey, ty + kPrefetchTileRows, tx0, tx1);
    int tx = tx0;
    // The default 8-pixel tiles sixteen at a time (128 pixels): the sampled rows folded
    // into each sixteen-byte column, then the columns' eight-byte groups folded together
    // (fold_groups_of_eight); then two at a time, folding each half on its own. Every
    // pixel of a sampled row is seen. The rows' addresses are taken once per tile row:
    // the byte stores below may alias anything, which made the compiler read `grey`'s
    // step and data again for every row of every tile.
    if (t == 8) {
      auto min_op = [](const auto& a, const auto& b) { return cv::v_min(a, b); };
      auto max_op = [](const auto& a, const auto& b) { return cv::v_max(a, b); };
      std::array<const std::uint8_t*, 8 / kStatStep> rows{};
      int sampled = 0;
      for (int y = ty * t; y < y_end; y += kStatStep)
        rows[static_cast<std::size_t>(sampled++)] = grey.ptr<std::uint8_t>(y);
      // Minima first, then maxima from the same 512 bytes, now in L1: eight vectors of
      // each at once would not fit SSE2's sixteen registers. A whole tile row samples four
      // rows, fixed at compile time so that the eight vectors stay in registers.
      auto fold_columns = [&]<int kRows>(std::integral_constant<int, kRows>, int x0, auto op) {
        std::array<v_uint8x16, 8> v;
        for (std::size_t k = 0; k < 8; ++k) {
          const int x = x0 + static_cast<int>(k) * 16;
          v[k] = load16(rows[0] + x);
          for (std::size_t r = 1; r < static_cast<std::size_t>(kRows); ++r) v[k] = op(v[k], load16(rows[r] + x));
        }
        return fold_groups_of_eight(v, op);
      };
      auto fold_sixteen_tiles = [&](auto rows_sampled) {
        for (; tx + 15 <= tx1 && (tx + 16) * 8 <= size_.width; tx += 16) {
          const std::size_t i = static_cast<std::size_t>(ty) * tiles_x_ + tx;
          cv::v_store(&tile_min_[i], fold_columns(rows_sampled, tx * 8, min_op));
          cv::v_store(&tile_max_[i], fold_columns(rows_sampled, tx * 8, max_op));
        }
      };
      static_assert(8 / kStatStep == 4, "a whole tile row samples four rows");
      switch (sampled) {
        case 4: fold_sixteen_tiles(std::integral_constant<int, 4>{}); break;
        case 3: fold_sixteen_tiles(std::integral_constant<int, 3>{}); break;
        case 2: fold_sixteen_tiles(std::integral_constant<int, 2>{}); break;
        default: fold_sixteen_tiles(std::integral_constant<int, 1>{}); break;
      }
      for (; tx + 1 <= tx1 && (tx + 2) * 8 <= size_.width; tx += 2) {
        v_uint8x16 mn = cv::v_setall_u8(0xFF), mx = cv::v_setzero_u8();
        for (int r = 0; r < sampled; ++r) {
          const v_uint8x16 v = load16(rows[static_cast<std::size_t>(r)] + tx * 8);
          mn = cv::v_min(mn, v);
          mx = cv::v_max(mx, v);
        }
        const std::size_t i = static_cast<std::size_t>(ty) * tiles_x_ + tx;
        store_half_results(fold_halves(mn, min_op), &tile_min_[i]);
        store_half_results(fold_halves(mx, max_op), &tile_max_[i]);
      }
    }
    // The tiles left (all of them for other tile sizes), pixel by pixel.
    for (; tx <= tx1; ++tx) {
      const int x_end = std::min(size_.width, (tx + 1) * t);
      std::uint8_t mn = 255, mx = 0;
      for (int y = ty * t; y < y_end; y += kStatStep) {
        const std::uint8_t* row = grey.ptr<std::uint8_t>(y);
        for (int x = tx * t; x < x_end; ++x) {
          mn = std::min(mn, row[x]);
          mx = std::max(mx, row[x]);
        }
      }
      tile_min_[ty * tiles_x_ + tx] = mn;
      tile_max_[ty * tiles_x_ + tx] = mx;
    }
  }
  // The threshold of a tile comes from its 3x3 neighbourhood so that a marker larger
  // than one tile sees one consistent threshold across its dark disc; done as two
  // separable passes (a row of three, then a column of three).
  // The ROI's own tiles; their neighbours (tx0..tx1, ty0..ty1) only lend statistics.
  const int ax = roi.x / t, bx = (roi.x + roi.width - 1) / t;
  const int ay = roi.y / t, by = (roi.y + roi.height - 1) / t;
  // Interior tiles have both neighbours: no clamping, so the loop vectorises; the
  // frame's edge tiles (if in the ROI) take a clamped neighbourhood.
  const int ix0 = std::max(ax, 1), ix1 = std::min(bx, tiles_x_ - 2);
  for (int ty = ty0; ty <= ty1; ++ty) {
    const std::size_t row = static_cast<std::size_t>(ty) * tiles_x_;
    const std::uint8_t* __restrict__ mins = &tile_min_[row];
    const std::uint8_t* __restrict__ maxs = &tile_max_[row];
    std::uint8_t* __restrict__ out_min = &row_min_scratch_[row];
    std::uint8_t* __restrict__ out_max = &row_max_scratch_[row];
    int tx = ix0;
    for (; tx + 16 <= ix1 + 1; tx += 16) {  // sixteen tiles per step
      cv::v_store(out_min + tx, cv::v_min(cv::v_min(load16(mins + tx - 1), load16(mins + tx)), load16(mins + tx + 1)));
      cv::v_store(out_max + tx, cv::v_max(cv::v_max(load16(maxs + tx - 1), load16(maxs + tx)), load16(maxs + tx + 1)));
    }
    for (; tx <= ix1; ++tx) {  // the rest one by one
      out_min[tx] = std::min(std::min(mins[tx - 1], mins[tx]), mins[tx + 1]);
      out_max[tx] = std::max(std::max(maxs[tx - 1], maxs[tx]), maxs[tx + 1]);
    }
    for (int tx : {ax, bx}) {
      if (tx >= ix0 && tx <= ix1) continue;
      const int l = std::max(0, tx - 1), r = std::min(tiles_x_ - 1, tx + 1);
      out_min[tx] = std::min({mins[l], mins[tx], mins[r]});
      out_max[tx] = std::max({maxs[l], maxs[tx], maxs[r]});
    }
  }
  // The darkest grey a tile's neighbourhood may have and still hold a marker's black,
  // as a fraction (in 1/256) of its brightest.
  const int black_ratio_256 = static_cast<int>(std::clamp(config_.max_black_to_white, 0.0, 1.0) * 255.0);
  for (int ty = ay; ty <= by; ++ty) {
    const std::size_t up = static_cast<std::size_t>(std::max(0, ty - 1)) * tiles_x_;
    const std::size_t row = static_cast<std::size_t>(ty) * tiles_x_;
    const std::size_t down = static_cast<std::size_t>(std::min(tiles_y_ - 1, ty + 1)) * tiles_x_;
    // __restrict__: the arrays are distinct, which lets the loop vectorise.
    const std::uint8_t* __restrict__ min_up = &row_min_scratch_[up];
    const std::uint8_t* __restrict__ min_row = &row_min_scratch_[row];
    const std::uint8_t* __restrict__ min_down = &row_min_scratch_[down];
    const std::uint8_t* __restrict__ max_up = &row_max_scratch_[up];
    const std::uint8_t* __restrict__ max_row = &row_max_scratch_[row];
    const std::uint8_t* __restrict__ max_down = &row_max_scratch_[down];
    std::uint8_t* __restrict__ range = &tile_range_[row];
    std::uint8_t* __restrict__ threshold = &tile_threshold_[row];
    int tx = ax;
    const v_uint16x8 ratio = cv::v_setall_u16(static_cast<std::uint16_t>(black_ratio_256));
    for (; tx + 16 <= bx + 1; tx += 16) {  // sixteen tiles per step
      const v_uint8x16 mn = cv::v_min(cv::v_min(load16(min_up + tx), load16(min_row + tx)), load16(min_down + tx));
      const v_uint8x16 mx = cv::v_max(cv::v_max(load16(max_up + tx), load16(max_row + tx)), load16(max_down + tx));
      const v_uint8x16 spread = cv::v_sub_wrap(mx, mn);
      cv::v_store(range + tx, spread);
      // The rounded-up average (mn + mx + 1) / 2 is mx - (mx - mn) / 2 (rounded down); the
      // bytes are halved in 16-bit lanes (no byte shifts), dropping the bit each takes
      // from its neighbour.
      const v_uint8x16 half_spread =
          cv::v_reinterpret_as_u8(cv::v_shr<1>(cv::v_reinterpret_as_u16(spread))) & cv::v_setall_u8(0x7F);
      const v_uint8x16 mid = cv::v_sub_wrap(mx, half_spread);
      // No black here where mn > mx * ratio / 256, in 16-bit lanes (grey levels: the
      // signed compare serves).
      v_uint16x8 mn_lo, mn_hi, mx_lo, mx_hi;
      cv::v_expand(mn, mn_lo, mn_hi);
      cv::v_expand(mx, mx_lo, mx_hi);
      auto light = [&](const v_uint16x8& mn16, const v_uint16x8& mx16) {
        return cv::v_reinterpret_as_s16(mn16) > cv::v_reinterpret_as_s16(cv::v_shr<8>(cv::v_mul_wrap(mx16, ratio)));
      };
      // Packing saturates: an all-ones 16-bit lane (-1) stays all ones.
      const v_uint8x16 no_black = cv::v_reinterpret_as_u8(cv::v_pack(light(mn_lo, mx_lo), light(mn_hi, mx_hi)));
      cv::v_store(threshold + tx, mid & ~no_black);
    }
    for (; tx <= bx; ++tx) {  // the rest one by one
      const std::uint8_t mn = std::min(std::min(min_up[tx], min_row[tx]), min_down[tx]);
      const std::uint8_t mx = std::max(std::max(max_up[tx], max_row[tx]), max_down[tx]);
      range[tx] = static_cast<std::uint8_t>(mx - mn);
      // (mn + mx + 1) / 2 without overflow: the rounded-up average of two bytes.
      const bool no_black = mn > ((mx * black_ratio_256) >> 8);
      threshold[tx] = no_black ? 0 : static_cast<std::uint8_t>((mn | mx) - ((mn ^ mx) >> 1));
    }
  }
  // Sensor noise alone spans some grey levels around every tile; a tile counts as
  // having contrast only well above that. The floor's contrast is the lower quartile of
  // these very ranges over a large search (a quarter of any frame is floor), kept for
  // the small tracked searches; a cap keeps a frame crowded with markers from raising
  // it to the markers' own contrast.
  if ((bx - ax + 1) * (by - ay + 1) * 4 >= tiles_x_ * tiles_y_) {
    std::array<int, 256> histogram{};
    int count = 0;
    // Every other tile of every other row is plenty for a quartile of thousands.
    for (int ty = ay; ty <= by; ty += 2) {
      const std::uint8_t* range = &tile_range_[static_cast<std::size_t>(ty) * tiles_x_];
      for (int tx = ax; tx <= bx; tx += 2) ++histogram[range[tx]];
      count += (bx - ax) / 2 + 1;
    }
    int seen = 0;
    for (int range = 0; range < 256; ++range) {  // quartile by counting
      seen += histogram[range];
      if (4 * seen > count) {
        floor_range_ = range;
        break;
      }
    }
  }
  const int min_contrast = std::max(
      config_.min_local_contrast,
      std::min(config_.max_noise_contrast, static_cast<int>(std::lround(config_.contrast_over_noise * floor_range_))));
  const auto floor_cut = static_cast<std::uint8_t>(std::clamp(min_contrast, 0, 255));
  for (int ty = ay; ty <= by; ++ty) {
    const std::size_t row = static_cast<std::size_t>(ty) * tiles_x_;
    const std::uint8_t* __restrict__ range = &tile_range_[row];
    std::uint8_t* __restrict__ threshold = &tile_threshold_[row];
    int tx = ax;
    const v_uint8x16 cut = cv::v_setall_u8(floor_cut);
    for (; tx + 16 <= bx + 1; tx += 16) {  // keep where range >= cut, i.e. max(range, cut) == range
      const v_uint8x16 r = load16(range + tx);
      cv::v_store(threshold + tx, (cv::v_max(r, cut) == r) & load16(threshold + tx));
    }
    for (; tx <= bx; ++tx) threshold[tx] = range[tx] < floor_cut ? 0 : threshold[tx];
    // The tiles with contrast, listed per tile row: the seed scan visits only these.
    std::int16_t* list = &contrast_tiles_[row];
    int n = 0;
    int tx_list = ax;
    // Sixteen tiles per step; a plain floor has no contrast tile in most steps.
    for (; tx_list + 16 <= bx + 1; tx_list += 16) {
      unsigned mask = nonzero_bits(threshold + tx_list);
      while (mask != 0) {
        list[n++] = static_cast<std::int16_t>(tx_list + __builtin_ctz(mask));
        mask &= mask - 1;
      }
    }
    for (; tx_list <= bx; ++tx_list) {
      list[n] = static_cast<std::int16_t>(tx_list);
      n += threshold[tx_list] != 0;
    }
    contrast_tile_count_[ty] = n;
  }
}

void BlobDetector::prefetch_sampled_rows(const cv::Mat& grey, int ty, int tx0, int tx1) const {
  if (ty >= tiles_y_) return;
  const int t = config_.tile_px;
  const int x0 = tx0 * t, x1 = std::min(size_.width, (tx1 + 1) * t) - 1;
  for (int y = ty * t; y < std::min(size_.height, (ty + 1) * t); y += kStatStep) {
    const std::uint8_t* row = grey.ptr<std::uint8_t>(y);
    for (int x = x0 & ~63; x <= x1; x += 64) __builtin_prefetch(row + x, 0, 1);
  }
}

void BlobDetector::prefetch_contrast_tiles(const cv::Mat& grey, int ty) const {
  if (ty >= tiles_y_) return;
  const int t = config_.tile_px;
  const std::int16_t* list = &contrast_tiles_[static_cast<std::size_t>(ty) * tiles_x_];
  const int listed = contrast_tile_count_[ty];
  for (int y = ty * t; y < std::min(size_.height, (ty + 1) * t); ++y) {
    const std::uint8_t* row = grey.ptr<std::uint8_t>(y);
    int last_line = -1;
    for (int i = 0; i < listed; ++i) {
      const int x = list[i] * t;
      if (x >> 6 == last_line) continue;  // one hint per cache line
      last_line = x >> 6;
      __builtin_prefetch(row + x, 0, 1);
    }
  }
}

void BlobDetector::build_dark_mask(const cv::Mat& grey, cv::Rect roi, bool local_thresholds) {
  const int t_px = config_.tile_px;
  const int tx0 = roi.x / t_px, tx1 = (roi.x + roi.width - 1) / t_px;
  const int ty0 = roi.y / t_px, ty1 = (roi.y + roi.height - 1) / t_px;
  std::vector<int>& contrast = mask_tiles_;  // tile columns with contrast in this tile row
  for (int ty = ty0; ty <= ty1; ++ty) {
    const int y0 = ty * t_px, y1 = std::min(size_.height, y0 + t_px);
    const std::size_t row = static_cast<std::size_t>(ty) * tiles_x_;
    contrast.clear();
    // Only tiles with a threshold or with an earlier search's mask need a look; sixteen
    // at a time, most of a plain floor is skipped in one compare.
    auto visit = [&](int tx) {
      const std::uint8_t t = tile_threshold_[row + tx];
      // A tile whose own pixels all lie just below its threshold is floor beside a
      // marker whose black only grazes the neighbourhood, not black: printed black lies
      // far below the midpoint. It would be filled whole, for nothing.
      // (Only with thresholds from this search's own tile statistics.)
      const bool floor_below = local_thresholds && t != 0 && tile_max_[row + tx] < t &&
                               5 * (t - tile_min_[row + tx]) < 2 * tile_range_[row + tx];
      if (t != 0 && !floor_below) {
        contrast.push_back(tx);
        dark_written_[row + tx] = 1;
      } else if (dark_written_[row + tx]) {
        // No contrast now, but an earlier search wrote this block: nothing is dark.
        const int x0 = tx * t_px, x1 = std::min(size_.width, x0 + t_px);
        for (int y = y0; y < y1; ++y) clear_span(dark_.ptr<std::uint8_t>(y), x0, x1 - 1);
        dark_written_[row + tx] = 0;
      }
    };
    int tx = tx0;
    for (; tx + 16 <= tx1 + 1; tx += 16) {
      unsigned bits = nonzero_bits(load16(&tile_threshold_[row + tx]) | load16(&dark_written_[row + tx]));
      while (bits != 0) {  // in increasing order: the list stays sorted
        visit(tx + __builtin_ctz(bits));
        bits &= bits - 1;
      }
    }
    for (; tx <= tx1; ++tx) visit(tx);
    // Row by row across the tile row (not tile by tile down it), so that the frame is
    // read as a stream: a new frame is not in the caches yet.
    const std::size_t listed = contrast.size();
    // The next tile row's list is this search's only with its own statistics.
    if (local_thresholds && ty + 1 <= ty1) prefetch_contrast_tiles(grey, ty + 1);
    if (t_px == 8) {
      // The default tiles, eight pixels per tile; two neighbouring tiles in one
      // sixteen-byte step. The steps' limits are set once per tile row, not per pixel row.
      // x < t is max(x, t - 1) == t - 1.
      // Sized once for the widest tile row, so that a step costs no growth check.
      if (mask_steps_.size() < static_cast<std::size_t>(tiles_x_)) mask_steps_.resize(tiles_x_);
      std::size_t steps = 0;
      int narrow_tile = -1;  // a last tile narrower than eight pixels, done byte by byte
      for (std::size_t i = 0; i < listed; ++i) {
        const int tx = contrast[i];
        const int x0 = tx * 8;
        if (x0 + 8 > size_.width) {
          narrow_tile = tx;
          continue;
        }
        const bool pair = i + 1 < listed && contrast[i + 1] == tx + 1 && x0 + 16 <= size_.width;
        const int tx2 = pair ? tx + 1 : tx;
        auto limit_of = [&](int x) { return static_cast<std::uint8_t>(tile_threshold_[row + x] - 1); };
        auto deep_of = [&](int x) {
          const std::uint8_t deep = deep_threshold(tile_threshold_[row + x], tile_range_[row + x], local_thresholds);
          return static_cast<std::uint8_t>(deep - 1);
        };
        auto halves = [](std::uint8_t first, std::uint8_t second) {
          return cv::v_combine_low(cv::v_setall_u8(first), cv::v_setall_u8(second));
        };
        MaskStep& step = mask_steps_[steps++];
        cv::v_store_aligned(step.limit.data(), halves(limit_of(tx), limit_of(tx2)));
        cv::v_store_aligned(step.deep_limit.data(), halves(deep_of(tx), deep_of(tx2)));
        step.x0 = x0;
        step.pair = pair;
        i += pair;
      }
      const v_uint8x16 dark_bit = cv::v_setall_u8(kDarkBit), deep_bit = cv::v_setall_u8(kDeepBit);
      for (int y = y0; y < y1; ++y) {
        const std::uint8_t* in = grey.ptr<std::uint8_t>(y);
        std::uint8_t* out = dark_.ptr<std::uint8_t>(y);
        for (const MaskStep& step : std::span(mask_steps_.data(), steps)) {
          // A single tile reads and writes its eight bytes only (the next may be unlisted).
          const v_uint8x16 v = step.pair ? load16(in + step.x0) : cv::v_load_low(in + step.x0);
          const v_uint8x16 limit = cv::v_load_aligned(step.limit.data());
          const v_uint8x16 deep_limit = cv::v_load_aligned(step.deep_limit.data());
          const v_uint8x16 bits =
              ((cv::v_max(v, limit) == limit) & dark_bit) | ((cv::v_max(v, deep_limit) == deep_limit) & deep_bit);
          if (step.pair) {
            cv::v_store(out + step.x0, bits);
          } else {
            cv::v_store_low(out + step.x0, bits);
          }
        }
        if (narrow_tile >= 0) mask_tile_row_bytes(in, out, row, narrow_tile, local_thresholds);
      }
      continue;
    }
    // Other tile sizes, byte by byte.
    for (int y = y0; y < y1; ++y) {
      const std::uint8_t* in = grey.ptr<std::uint8_t>(y);
      std::uint8_t* out = dark_.ptr<std::uint8_t>(y);
      for (std::size_t i = 0; i < listed; ++i) mask_tile_row_bytes(in, out, row, contrast[i], local_thresholds);
    }
  }
}

void BlobDetector::mask_tile_row_bytes(const std::uint8_t* in, std::uint8_t* out, std::size_t tile_row_index, int tx,
                                       bool local_thresholds) const {
  const std::uint8_t t = tile_threshold_[tile_row_index + tx];
  const std::uint8_t deep = deep_threshold(t, tile_range_[tile_row_index + tx], local_thresholds);
  const int x0 = tx * config_.tile_px, x1 = std::min(size_.width, x0 + config_.tile_px);
  for (int x = x0; x < x1; ++x) out[x] = (in[x] < t ? kDarkBit : 0) | (in[x] < deep ? kDeepBit : 0);
}

namespace {

// The first and last pixel of the run of nonzero mask bytes through `x` (mask[x] != 0),
// in a row with zero padding on both sides (so every run ends inside the buffer).
int run_start(const std::uint8_t* mask, int x) {
  for (;;) {  // sixteen bytes ending at x, looking for the last zero
    const unsigned zeros = nonzero_bits(mask + x - 15) ^ 0xFFFFu;
    if (zeros != 0) return x - 15 + (31 - __builtin_clz(zeros)) + 1;
    x -= 16;
  }
}

int run_end(const std::uint8_t* mask, int x) {
  for (;;) {  // sixteen bytes starting at x, looking for the first zero
    const unsigned zeros = nonzero_bits(mask + x) ^ 0xFFFFu;
    if (zeros != 0) return x + __builtin_ctz(zeros) - 1;
    x += 16;
  }
}

// Calls `seed(x)` once per run of nonzero mask bytes within [a, b], at the run's first
// pixel in that range.
template <class SeedFn>
void for_each_run(const std::uint8_t* mask, int a, int b, SeedFn&& seed) {
  unsigned carry = 0;  // the pixel before the chunk was dark (and in range)
  for (int x = a; x <= b; x += 16) {
    unsigned bits = nonzero_bits(mask + x);
    if (b - x < 15) bits &= (1u << (b - x + 1)) - 1;
    unsigned starts = bits & ~((bits << 1) | carry);
    while (starts != 0) {
      seed(x + __builtin_ctz(starts));
      starts &= starts - 1;
    }
    carry = (bits >> 15) & 1u;
  }
}

// The first and the last nonzero mask byte in [a, b], or -1 when there is none.
int first_dark(const std::uint8_t* mask, int a, int b) {
  for (int x = a; x <= b; x += 16) {
    unsigned bits = nonzero_bits(mask + x);
    if (b - x < 15) bits &= (1u << (b - x + 1)) - 1;
    if (bits != 0) return x + __builtin_ctz(bits);
  }
  return -1;
}

int last_dark(const std::uint8_t* mask, int a, int b) {
  for (int x = b; x >= a; x -= 16) {  // sixteen bytes ending at x
    unsigned bits = nonzero_bits(mask + x - 15);
    if (x - a < 15) bits &= ~((1u << (15 - (x - a))) - 1);
    if (bits != 0) return x - 15 + (31 - __builtin_clz(bits));
  }
  return -1;
}

// How many mask bytes in [a, b] are nonzero, for a span of at most 255 * 16 bytes:
// min(byte, 1) summed per byte lane (255 at most) and the lanes summed once at the end (no
// population count: not in baseline x86-64).
constexpr int kMaxCountedSpan = 255 * 16;
int count_nonzero_span(const std::uint8_t* mask, int a, int b) {
  const v_uint8x16 one = cv::v_setall_u8(1);
  v_uint8x16 ones = cv::v_setzero_u8();
  int x = a;
  for (; x + 15 <= b; x += 16) ones += cv::v_min(load16(mask + x), one);
  if (x <= b) {
    // The last few bytes in one step: the row's zero padding keeps the load inside the
    // buffer, and the bytes beyond b are masked off.
    alignas(16) static constexpr std::uint8_t kOnes[32] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};
    ones += cv::v_min(load16(mask + x), load16(kOnes + 16 - (b - x + 1)));
  }
  return static_cast<int>(cv::v_reduce_sum(ones));
}

// How many mask bytes in [a, b] are nonzero (a marker's row is one span).
int count_nonzero(const std::uint8_t* mask, int a, int b) {
  int count = 0;
  for (; b - a + 1 > kMaxCountedSpan; a += kMaxCountedSpan) {
    count += count_nonzero_span(mask, a, a + kMaxCountedSpan - 1);
  }
  return count + count_nonzero_span(mask, a, b);
}

}  // namespace

bool BlobDetector::sweep_fill(cv::Rect roi, int seed_x, int seed_y, Fill& fill) {
  const double max_disc_d = config_.max_diameter_px * kDiscFraction;
  const int max_area = static_cast<int>(kPi * max_disc_d * max_disc_d / 4.0 * 1.3) + 16;
  const int max_extent = static_cast<int>(max_disc_d * 1.2) + 2;
  const int rx0 = roi.x, rx1 = roi.x + roi.width - 1, ry0 = roi.y, ry1 = roi.y + roi.height - 1;
  auto mask_row = [&](int y) { return dark_.ptr<std::uint8_t>(y); };
  int top = seed_y, bottom = seed_y;
  row_min_x_[seed_y] = std::max(rx0, run_start(mask_row(seed_y), seed_x));
  row_max_x_[seed_y] = std::min(rx1, run_end(mask_row(seed_y), seed_x));
  // Widens row y's extent by every run that overlaps [a, b] (the neighbouring row's
  // extent joined with its own); false when the row has nothing dark there.
  auto grow = [&](int y, int a, int b) {
    const std::uint8_t* mask = mask_row(y);
    const int l = row_min_x_[y], r = row_max_x_[y];
    if (r < l) {  // a new row
      const int first = first_dark(mask, a, b);
      if (first < 0) return false;
      row_min_x_[y] = std::max(rx0, run_start(mask, first));
      row_max_x_[y] = std::min(rx1, run_end(mask, last_dark(mask, first, b)));
      return true;
    }
    // Only the parts of [a, b] beside the extent can add to it (the pixels just outside
    // an extent are not dark: it ends where its runs do).
    bool grew = false;
    if (a < l) {
      const int first = first_dark(mask, a, l - 1);
      if (first >= 0) {
        row_min_x_[y] = std::max(rx0, run_start(mask, first));
        grew = true;
      }
    }
    if (b > r) {
      const int last = last_dark(mask, r + 1, b);
      if (last >= 0) {
        row_max_x_[y] = std::min(rx1, run_end(mask, last));
        grew = true;
      }
    }
    return grew;
  };
  // Sweeps down, up and down again (and so on) until one changes nothing: three for a
  // marker seeded anywhere on its disc, as each row's extent only grows by what
  // touches its neighbour's. A row is looked at again only when the neighbour the sweep
  // comes from changed in this sweep or the one before (`row_stamp_`: the sweep in which
  // a row last changed); otherwise it already holds all that touches that neighbour.
  bool ok = true;
  constexpr int kMaxSweeps = 6;
  int sweep = 1;
  row_stamp_[seed_y] = 1;
  for (bool changed = true, down = true; changed && ok; down = !down, ++sweep) {
    if (sweep > kMaxSweeps) {
      ok = false;
      break;
    }
    changed = false;
    const int dir = down ? 1 : -1;
    for (int y = (down ? top : bottom) + dir; y >= ry0 && y <= ry1; y += dir) {
      const bool is_new = y > bottom || y < top;
      if (!is_new && row_stamp_[y - dir] < sweep - 1) continue;
      const bool grew = grow(y, row_min_x_[y - dir], row_max_x_[y - dir]);
      if (grew) {
        changed = true;
        row_stamp_[y] = sweep;
      }
      if (row_max_x_[y] - row_min_x_[y] > max_extent) ok = false;  // no marker: stop early
      if (is_new) {
        if (!grew) break;
        (down ? bottom : top) = y;
      }
      if (!ok || bottom - top > max_extent) break;
    }
    if (bottom - top > max_extent) ok = false;
    // The first two sweeps always change something; a third that changes nothing ends.
    if (sweep == 1) changed = true;
  }
  fill = Fill{0, 0, rx1, rx0, top, bottom, false, false};
  for (int y = top; y <= bottom && ok; ++y) {
    fill.x0 = std::min(fill.x0, row_min_x_[y]);
    fill.x1 = std::max(fill.x1, row_max_x_[y]);
    fill.area += count_nonzero(mask_row(y), row_min_x_[y], row_max_x_[y]);
    fill.extent_area += row_max_x_[y] - row_min_x_[y] + 1;
  }
  fill.touches_border = fill.x0 == rx0 || fill.x1 == rx1 || top == ry0 || bottom == ry1;
  if (!ok || fill.area > max_area || fill.x1 - fill.x0 > max_extent || fill.touches_border) {
    clear_row_extents(top, bottom);
    return false;
  }
  return true;
}

void BlobDetector::clear_row_extents(int y0, int y1) {
  for (int y = y0; y <= y1; ++y) {
    row_min_x_[y] = 0;
    row_max_x_[y] = -1;
  }
}

bool BlobDetector::flood_fill(cv::Rect roi, int seed_x, int seed_y, Fill& fill) {
  const double max_disc_d = config_.max_diameter_px * kDiscFraction;
  const int max_area = static_cast<int>(kPi * max_disc_d * max_disc_d / 4.0 * 1.3) + 16;
  // A region far beyond any marker is still labelled (so it is not seeded again and
  // again) up to this bound, which keeps the worst case linear in the frame size.
  const int hard_limit = std::max(max_area * 4, 4096);
  // No marker's disc is wider or taller than this (tilt only shrinks one axis).
  const int max_extent = static_cast<int>(max_disc_d * 1.2) + 2;
  const int rx0 = roi.x, rx1 = roi.x + roi.width - 1, ry0 = roi.y, ry1 = roi.y + roi.height - 1;
  fill = Fill{0, 0, seed_x, seed_x, seed_y, seed_y, false, false};

  // A stack of seeds, each with the span of the row it was found from: that span is
  // already filled, so the seed's own span need not look back into it.
  std::vector<FillSeed>& stack = fill_stack_;
  stack.clear();
  stack.push_back({seed_x, seed_y, seed_y, 1, 0});
  while (!stack.empty()) {
    const FillSeed seed = stack.back();
    stack.pop_back();
    const int y = seed.y;
    std::uint8_t* dark = dark_.ptr<std::uint8_t>(y);
    if (!dark[seed.x]) continue;  // filled since it was pushed
    const int xl = std::max(rx0, run_start(dark, seed.x));
    const int xr = std::min(rx1, run_end(dark, seed.x));
    clear_span(dark, xl, xr);
    fill.area += xr - xl + 1;
    if (xl == rx0 || xr == rx1 || y == ry0 || y == ry1) fill.touches_border = true;
    fill.x0 = std::min(fill.x0, xl);
    fill.x1 = std::max(fill.x1, xr);
    fill.y0 = std::min(fill.y0, y);
    fill.y1 = std::max(fill.y1, y);
    if (row_max_x_[y] < row_min_x_[y]) {
      row_min_x_[y] = xl;
      row_max_x_[y] = xr;
    } else {
      row_min_x_[y] = std::min(row_min_x_[y], xl);
      row_max_x_[y] = std::max(row_max_x_[y], xr);
    }
    if (fill.area > max_area || fill.x1 - fill.x0 > max_extent || fill.y1 - fill.y0 > max_extent) fill.too_large = true;
    if (fill.area > hard_limit) break;
    for (int ny : {y - 1, y + 1}) {
      if (ny < ry0 || ny > ry1) continue;
      const std::uint8_t* ndark = dark_.ptr<std::uint8_t>(ny);
      // On the parent's row, the part under the parent's span is filled: skip it.
      auto push = [&](int x) { stack.push_back({x, ny, y, xl, xr}); };
      if (ny == seed.parent_y) {
        for_each_run(ndark, xl, std::min(xr, seed.parent_x0 - 1), push);
        for_each_run(ndark, std::max(xl, seed.parent_x1 + 1), xr, push);
      } else {
        for_each_run(ndark, xl, xr, push);
      }
    }
  }
  return !fill.too_large && !fill.touches_border;
}

namespace {

// Position, between pixel centres `outside` and `inside`, where the grey level crosses
// the threshold (linear interpolation). Returns the offset from `inside` towards
// `outside` in [0, 1].
double edge_offset(double outside_level, double inside_level, double threshold) {
  const double span = outside_level - inside_level;
  if (span <= 0.0) return 0.5;
  return std::clamp((threshold - inside_level) / span, 0.0, 1.0);
}

// Running sums of the moments of a region built from parallel chords.
struct ChordMoments {
  double area = 0, along = 0, along2 = 0, cross_along = 0, cross = 0;
  // A chord [a, b] (along the chord's axis) at position c (across). The integrals'
  // constant factors (1/2 and 1/3) are applied once, in finish(): a division per chord
  // would cost more than the rest of the sum.
  void add(double a, double b, double c) {
    const double len = b - a, sq = b * b - a * a;
    area += len;
    along += sq;
    along2 += b * b * b - a * a * a;
    cross_along += c * sq;
    cross += c * len;
  }
  void finish() {
    along *= 0.5;
    along2 *= 1.0 / 3.0;
    cross_along *= 0.5;
  }
};

// Mean deviation of the chords {a, b, position across} from those of the ellipse whose
// quadratic form is q_along*s^2 + 2*q_mixed*s*d + q_across*d^2 = 1 around
// (centre_along, centre_across): the difference in length plus the offset of the
// midpoint, over the number of chords and the longest chord. Two chords per step in
// vector lanes (two square roots in one instruction): this ran once per chord per candidate.
double chord_error(const std::vector<std::array<double, 3>>& chords, double q_along, double q_mixed, double q_across,
                   double centre_along, double centre_across) {
  const double inv_q_along = 1.0 / q_along;
  // The chord at offset d has half-length sqrt(disc) / q_along, with
  // disc = q_mixed^2 d^2 - q_along (q_across d^2 - 1) = q_along + k2 d^2.
  const double k2 = q_mixed * q_mixed - q_along * q_across;
  const double mid_slope = q_mixed * inv_q_along;
  double err = 0.0, longest = 0.0;
  std::size_t i = 0;
  const v_float64x2 v_k0 = cv::v_setall_f64(q_along), v_k2 = cv::v_setall_f64(k2);
  const v_float64x2 v_two_inv = cv::v_setall_f64(2.0 * inv_q_along);
  const v_float64x2 v_centre_across = cv::v_setall_f64(centre_across), v_centre_along = cv::v_setall_f64(centre_along);
  const v_float64x2 v_slope = cv::v_setall_f64(mid_slope), v_half = cv::v_setall_f64(0.5), v_zero = cv::v_setzero_f64();
  v_float64x2 v_err = cv::v_setzero_f64(), v_longest = cv::v_setzero_f64();
  for (; i + 2 <= chords.size(); i += 2) {
    const v_float64x2 a(chords[i][0], chords[i + 1][0]);
    const v_float64x2 b(chords[i][1], chords[i + 1][1]);
    const v_float64x2 d = v_float64x2(chords[i][2], chords[i + 1][2]) - v_centre_across;
    const v_float64x2 disc = v_k0 + v_k2 * (d * d);
    const v_float64x2 model = cv::v_sqrt(cv::v_max(disc, v_zero)) * v_two_inv;
    v_longest = cv::v_max(v_longest, model);
    const v_float64x2 mid_model = v_centre_along - v_slope * d;
    v_err += cv::v_abs((b - a) - model) + cv::v_abs(v_half * (a + b) - mid_model);
  }
  err = cv::v_reduce_sum(v_err);  // lane 0 + lane 1
  longest = std::max(cv::v_extract_n<0>(v_longest), cv::v_extract_n<1>(v_longest));
  // An odd chord left over.
  for (; i < chords.size(); ++i) {
    const auto& c = chords[i];
    const double d = c[2] - centre_across;
    const double disc = q_along + k2 * d * d;
    const double model = disc > 0.0 ? 2.0 * std::sqrt(disc) * inv_q_along : 0.0;
    longest = std::max(longest, model);
    // The chord's midpoint must also sit where the ellipse's does.
    const double mid_model = centre_along - mid_slope * d;
    err += std::abs((c[1] - c[0]) - model) + std::abs(0.5 * (c[0] + c[1]) - mid_model);
  }
  return longest > 0.0 ? err / (chords.size() * longest) : 1.0;
}

}  // namespace

bool BlobDetector::measure(const cv::Mat& grey, const Fill& fill, Blob& blob) {
  // Sub-pixel chords along rows (for x moments) and along columns (for y moments).
  ChordMoments rows, cols;
  std::vector<std::array<double, 3>>& row_chords = row_chords_;  // {a, b, position}
  std::vector<std::array<double, 3>>& col_chords = col_chords_;
  row_chords.clear();
  col_chords.clear();
  row_chords.reserve(fill.y1 - fill.y0 + 1);
  // A marker's disc is bounded by bright pixels (its white ring, or a light floor). A
  // region that ends where the local contrast ends instead (a dark floor around a
  // marker, cut off by tiles without contrast) is not a disc.
  int bright_edges = 0, edges = 0;
  auto bright = [&](int x, int y) {
    const std::uint8_t t = threshold_at(x, y);
    return t != 0 && grey.at<std::uint8_t>(y, x) >= t ? 1 : 0;
  };
  col_chords.reserve(fill.x1 - fill.x0 + 1);
  for (int y = fill.y0; y <= fill.y1; ++y) {
    const int xl = row_min_x_[y], xr = row_max_x_[y];
    if (xr < xl) continue;
    const std::uint8_t* row = grey.ptr<std::uint8_t>(y);
    if (xl > 0) bright_edges += bright(xl - 1, y);
    if (xr + 1 < grey.cols) bright_edges += bright(xr + 1, y);
    edges += 2;
    double a = xl - 0.5, b = xr + 0.5;
    if (xl > 0) a = xl - edge_offset(row[xl - 1], row[xl], threshold_at(xl, y));
    if (xr + 1 < grey.cols) b = xr + edge_offset(row[xr + 1], row[xr], threshold_at(xr, y));
    rows.add(a, b, y);
    row_chords.push_back({a, b, static_cast<double>(y)});
  }
  const double least_bright = exact_fills_ ? inside_bright_outline_ : config_.min_bright_outline;
  // Too few bright row ends for the outline to pass even if every column end is bright:
  // turned away before the columns are read (most of a textured floor's regions).
  if (bright_edges + 2 * (fill.x1 - fill.x0 + 1) < least_bright * (edges + 2 * (fill.x1 - fill.x0 + 1))) {
    last_rejection_ = RegionRejection::kDimOutline;
    return false;
  }
  // Column extents only for the regions that get this far (a long strip of tape is
  // filled, but never measured; most specks of a textured floor end just above).
  find_column_extents(fill);
  for (int x = fill.x0; x <= fill.x1; ++x) {
    const int yt = col_min_y_[x], yb = col_max_y_[x];
    if (yb < yt) continue;
    if (yt > 0) bright_edges += bright(x, yt - 1);
    if (yb + 1 < grey.rows) bright_edges += bright(x, yb + 1);
    edges += 2;
    double a = yt - 0.5, b = yb + 0.5;
    if (yt > 0)
      a = yt - edge_offset(grey.at<std::uint8_t>(yt - 1, x), grey.at<std::uint8_t>(yt, x), threshold_at(x, yt));
    if (yb + 1 < grey.rows)
      b = yb + edge_offset(grey.at<std::uint8_t>(yb + 1, x), grey.at<std::uint8_t>(yb, x), threshold_at(x, yb));
    cols.add(a, b, x);
    col_chords.push_back({a, b, static_cast<double>(x)});
  }
  auto reject = [&](RegionRejection why) {
    last_rejection_ = why;
    return false;
  };
  if (rows.area <= 0.0 || cols.area <= 0.0) return reject(RegionRejection::kDegenerate);
  if (bright_edges < least_bright * edges) return reject(RegionRejection::kDimOutline);

  rows.finish();
  cols.finish();
  const double cx = rows.along / rows.area;
  const double cy = cols.along / cols.area;
  const double sxx = rows.along2 / rows.area - cx * cx;
  const double syy = cols.along2 / cols.area - cy * cy;
  const double sxy = 0.5 * (rows.cross_along / rows.area - cx * rows.cross / rows.area + cols.cross_along / cols.area -
                            cy * cols.cross / cols.area);
  const double det = sxx * syy - sxy * sxy;
  if (sxx <= 0.0 || syy <= 0.0 || det <= 0.0) return reject(RegionRejection::kDegenerate);

  // Axis ratio from the eigenvalues of the covariance.
  const double mean = 0.5 * (sxx + syy);
  const double diff = std::sqrt(0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy);
  const double l_major = mean + diff, l_minor = mean - diff;
  if (l_minor <= 0.0 || std::sqrt(l_major / l_minor) > config_.max_axis_ratio)
    return reject(RegionRejection::kElongated);

  // A uniform ellipse with covariance S has outline q^T (4S)^-1 q = 1 and area 4*pi*sqrt(det S).
  const double ellipse_area = 4.0 * kPi * std::sqrt(det);
  const double area = 0.5 * (rows.area + cols.area);
  if (std::abs(area - ellipse_area) > config_.max_area_error * ellipse_area)
    return reject(RegionRejection::kAreaMismatch);

  const double inv = 1.0 / (4.0 * det);
  const double qxx = syy * inv, qyy = sxx * inv, qxy = -sxy * inv;
  const double chord_limit = std::max(config_.max_chord_error, config_.max_doubtful_chord_error);
  const double row_err = chord_error(row_chords, qxx, qxy, qyy, cx, cy);
  if (row_err > chord_limit) return reject(RegionRejection::kRaggedOutline);
  const double col_err = chord_error(col_chords, qyy, qxy, qxx, cy, cx);
  if (col_err > chord_limit) return reject(RegionRejection::kRaggedOutline);
  blob.doubtful = std::max(row_err, col_err) > config_.max_chord_error;

  // Symmetric square root of 4S maps the unit circle onto the outline.
  const double s = std::sqrt(det);
  const double t = std::sqrt(sxx + syy + 2.0 * s);
  blob.shape = cv::Matx22d(sxx + s, sxy, sxy, syy + s) * (2.0 / t);
  blob.u = cx;
  blob.v = cy;
  blob.filled_area_px = area;
  blob.threshold = threshold_at(std::clamp(static_cast<int>(cx), 0, grey.cols - 1),
                                std::clamp(static_cast<int>(cy), 0, grey.rows - 1));
  return true;
}

bool BlobDetector::begin_search(const cv::Mat& grey, cv::Rect& roi, std::optional<double> fixed_threshold) {
  CV_Assert(grey.type() == CV_8UC1);
  prepare(grey);
  roi &= cv::Rect(0, 0, grey.cols, grey.rows);
  if (roi.width < 3 || roi.height < 3) return false;
  if (fixed_threshold) {
    const auto t = static_cast<std::uint8_t>(std::clamp(*fixed_threshold, 1.0, 255.0));
    const int t_px = config_.tile_px;
    for (int ty = roi.y / t_px; ty <= (roi.y + roi.height - 1) / t_px; ++ty) {
      for (int tx = roi.x / t_px; tx <= (roi.x + roi.width - 1) / t_px; ++tx) tile_threshold_[ty * tiles_x_ + tx] = t;
    }
  } else {
    compute_thresholds(grey, roi);
  }
  build_dark_mask(grey, roi, !fixed_threshold);
  return true;
}

bool BlobDetector::try_seed(const cv::Mat& grey, cv::Rect roi, int x, int y, Blob& blob) {
  ++fill_count_;
  Fill fill;
  // The sweep first: it finds a marker's disc at a fraction of the fill's cost. Its
  // region is kept only when it is a disc at least half dark (a marker's black ring
  // alone is half its disc): a region that is not, such as the floor around a marker
  // on a dark mat or a circular floor track around robots, may enclose dark shapes
  // that are not connected to it, and only the true fill tells them apart.
  if (!exact_fills_ && sweep_fill(roi, x, y, fill)) {
    // A swept region holds every dark region it touches, whole: when all of it is too
    // small for a disc, so is everything in it, and the exact fill is not needed. Most
    // of a textured floor's dark specks end here, at the cost of one sweep.
    if (fill.extent_area < min_disc_area()) {
      clear_swept_region(fill);
      reset_region(fill);
      return false;
    }
    // A marker's centre is its black hole; a dark ring around some other shape has its
    // hole there. (A centre lighter than the threshold only sends a marker to the fill.)
    // (A doubtful outline is left to the exact fill too: the sweep may have taken in
    // what lies around the disc.)
    const bool ok = fill.area >= kMinDarkFraction * fill.extent_area && measure_region(grey, fill, blob) &&
                    !blob.doubtful && centre_is_dark(blob);
    if (ok) clear_swept_region(fill);
    reset_region(fill);
    if (ok) return true;
  }
  const bool whole = flood_fill(roi, x, y, fill);
  const bool ok = whole && measure_region(grey, fill, blob);
  if (!ok && rejections_ != nullptr) {
    if (whole) {
      rejections_->push_back({0.5 * (fill.x0 + fill.x1), 0.5 * (fill.y0 + fill.y1),
                              static_cast<double>(std::max(fill.x1 - fill.x0, fill.y1 - fill.y0) + 1),
                              last_rejection_});
    } else {
      rejections_->push_back({static_cast<double>(x), static_cast<double>(y), 0.0, RegionRejection::kCut});
    }
  }
  reset_region(fill);
  return ok;
}

void BlobDetector::clear_swept_region(const Fill& fill) {
  for (int r = fill.y0; r <= fill.y1; ++r) {
    std::uint8_t* mask = dark_.ptr<std::uint8_t>(r);
    clear_span(mask, row_min_x_[r], row_max_x_[r]);
  }
}

double BlobDetector::min_disc_area() const {
  const double min_disc_d = config_.min_diameter_px * kDiscFraction;
  return kPi * min_disc_d * min_disc_d / 4.0 / config_.max_axis_ratio * 0.8;
}

bool BlobDetector::could_be_ellipse(const Fill& fill) const {
  long extent_area = 0;
  for (int r = fill.y0; r <= fill.y1; ++r) {
    if (row_max_x_[r] >= row_min_x_[r]) extent_area += row_max_x_[r] - row_min_x_[r] + 1;
  }
  const int w = fill.x1 - fill.x0 + 1, h = fill.y1 - fill.y0 + 1;
  // An ellipse of axis ratio r fills at least pi r / (2 (1 + r^2)) of its bounding box
  // (turned 45 degrees; pi/4 upright), and its box is at most r times as long as wide.
  // measure() allows the area max_area_error and the outline some chord error: the
  // margins below keep every region it would accept.
  const double r = config_.max_axis_ratio;
  const double least_fill = 0.75 * (1.0 - config_.max_area_error) * kPi * r / (2.0 * (1.0 + r * r));
  return extent_area >= least_fill * w * h && std::max(w, h) <= 1.3 * r * std::min(w, h) + 2;
}

bool BlobDetector::centre_is_dark(const Blob& blob) const {
  const int x = static_cast<int>(std::lround(blob.u)), y = static_cast<int>(std::lround(blob.v));
  return x >= 0 && y >= 0 && x < size_.width && y < size_.height && dark_.at<std::uint8_t>(y, x) != 0;
}

bool BlobDetector::measure_region(const cv::Mat& grey, const Fill& fill, Blob& blob) {
  if (fill.area < min_disc_area()) {
    last_rejection_ = RegionRejection::kTooSmall;
    return false;
  }
  if (!could_be_ellipse(fill)) {
    last_rejection_ = RegionRejection::kNotCompact;
    return false;
  }
  return measure(grey, fill, blob);
}

void BlobDetector::find_column_extents(const Fill& fill) {
  // A column's bottom is the last row (going down) that covers it and its top the last
  // going up: two plain fills per row, which vectorise, where one pass needed a compare
  // per column.
  for (int r = fill.y0; r <= fill.y1; ++r) {
    if (row_max_x_[r] >= row_min_x_[r]) std::fill(&col_max_y_[row_min_x_[r]], &col_max_y_[row_max_x_[r]] + 1, r);
  }
  for (int r = fill.y1; r >= fill.y0; --r) {
    if (row_max_x_[r] >= row_min_x_[r]) std::fill(&col_min_y_[row_min_x_[r]], &col_min_y_[row_max_x_[r]] + 1, r);
  }
}

void BlobDetector::reset_region(const Fill& fill) {
  // Reset the chord bookkeeping of the rows and columns the region touched.
  clear_row_extents(fill.y0, fill.y1);
  for (int c = fill.x0; c <= fill.x1; ++c) {
    col_min_y_[c] = 0;
    col_max_y_[c] = -1;
  }
}

std::vector<Blob> BlobDetector::scan(const cv::Mat& grey, cv::Rect roi, cv::Rect seeds) {
  std::vector<Blob> blobs;
  const double min_disc_d = config_.min_diameter_px * kDiscFraction;
  const int step = config_.seed_row_step > 0 ? config_.seed_row_step : std::max(1, static_cast<int>(min_disc_d / 4.0));
  seeds &= roi;
  for (int y = roi.y + step / 2; y < roi.y + roi.height; y += step) {
    if (y < seeds.y || y >= seeds.y + seeds.height) continue;
    const std::uint8_t* dark = dark_.ptr<std::uint8_t>(y);
    const std::size_t tile_row = static_cast<std::size_t>(tile_row_[y]) * tiles_x_;
    const int x_end = seeds.x + seeds.width;
    // Only the tiles with contrast (listed when their thresholds were set): a tile
    // without contrast holds no dark pixel, and most of a plain floor is such tiles.
    const std::int16_t* list = &contrast_tiles_[tile_row];
    const int listed = contrast_tile_count_[tile_row_[y]];
    for (int i = 0; i < listed; ++i) {
      const int tx = list[i];
      const int xa = std::max(seeds.x, tx * config_.tile_px), xb = std::min(x_end, (tx + 1) * config_.tile_px);
      if (xa >= xb) continue;
      // Most contrast tiles hold no pixel dark enough to seed a fill on a given seed row
      // (the bright side of an edge): one load of eight mask bytes skips them.
      if (xb - xa == 8) {
        constexpr std::uint64_t kDeepBytes = 0x0202020202020202ULL;
        std::uint64_t eight;
        std::memcpy(&eight, dark + xa, sizeof eight);
        if ((eight & kDeepBytes) == 0) continue;
      }
      for (int x = xa; x < xb; ++x) {
        if (!(dark[x] & kDeepBit)) continue;
        Blob blob;
        if (try_seed(grey, roi, x, y, blob)) blobs.push_back(blob);
      }
    }
  }
  return blobs;
}

std::vector<Blob> BlobDetector::detect(const cv::Mat& grey, cv::Rect roi) {
  if (!begin_search(grey, roi)) return {};
  return scan(grey, roi, roi);
}

std::vector<Blob> BlobDetector::detect_inside(const cv::Mat& grey, cv::Rect roi, double min_bright_outline,
                                              std::optional<cv::Rect> seeds) {
  exact_fills_ = true;
  inside_bright_outline_ = min_bright_outline;
  std::vector<Blob> blobs;
  if (begin_search(grey, roi)) blobs = scan(grey, roi, seeds.value_or(roi));
  exact_fills_ = false;
  return blobs;
}

bool BlobDetector::seed_near(const cv::Mat& grey, cv::Rect roi, cv::Point2d expected_px, Blob& blob) {
  const int y = static_cast<int>(std::lround(expected_px.y));
  const int x0 = static_cast<int>(std::lround(expected_px.x));
  if (y <= roi.y || y >= roi.y + roi.height - 1 || x0 <= roi.x || x0 >= roi.x + roi.width - 1) return false;
  // Walk outwards from the prediction to the first dark pixel: the marker's hole, a dark
  // slice or its black ring, all parts of the one dark disc.
  const std::uint8_t* dark = dark_.ptr<std::uint8_t>(y);
  for (int d = 0; d < roi.width / 2; ++d) {
    for (int x : {x0 - d, x0 + d}) {
      if (x <= roi.x || x >= roi.x + roi.width - 1 || !dark[x]) continue;
      // The dark region nearest the prediction is the marker, or the prediction failed.
      return try_seed(grey, roi, x, y, blob) &&
             std::hypot(blob.u - expected_px.x, blob.v - expected_px.y) < 0.5 * blob.disc_diameter_px();
    }
  }
  return false;
}

std::vector<Blob> BlobDetector::detect_near(const cv::Mat& grey, cv::Rect roi, cv::Point2d expected_px,
                                            std::optional<double> threshold_grey) {
  Blob blob;
  if (threshold_grey) {
    cv::Rect r = roi;
    if (begin_search(grey, r, threshold_grey) && seed_near(grey, r, expected_px, blob)) return {blob};
  }
  if (!begin_search(grey, roi)) return {};
  if (seed_near(grey, roi, expected_px, blob)) return {blob};
  return scan(grey, roi, roi);
}

}  // namespace rilbed::vision
