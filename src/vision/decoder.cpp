#include "vision/decoder.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <tuple>

#include <opencv2/core/hal/intrin.hpp>

#include "core/fast_trig.hpp"
#include "core/geometry.hpp"
#include "vision/circle_sampler.hpp"

namespace rilbed::vision {

namespace {

// The kernels below are written once with OpenCV's universal intrinsics (SSE2 on x86,
// NEON on ARM, OpenCV's C++ emulation elsewhere): sixteen bytes or two doubles per vector.
using cv::v_float64x2;
using cv::v_uint8x16;

// How many of the `span` (a multiple of sixteen, at most 255 * 16) levels are at most
// `level`: per byte lane, a true compare (all ones: -1) is added, counting down from
// zero (255 steps at most), and the lanes are negated and summed once.
constexpr int kMaxCountedSpan = 255 * 16;
int count_span_at_or_below(const std::uint8_t* levels, int span, const v_uint8x16& level) {
  v_uint8x16 minus_counts = cv::v_setzero_u8();
  for (int i = 0; i < span; i += 16) {
    const v_uint8x16 v = cv::v_load(levels + i);
    minus_counts = cv::v_add_wrap(minus_counts, cv::v_min(v, level) == v);  // v <= level
  }
  return static_cast<int>(cv::v_reduce_sum(cv::v_sub_wrap(cv::v_setzero_u8(), minus_counts)));
}

// The same for any multiple of sixteen levels (no decoder samples more than one span).
int count_at_or_below(const std::uint8_t* levels, int padded, int level) {
  const v_uint8x16 l = cv::v_setall_u8(static_cast<std::uint8_t>(level));
  int count = 0;
  for (; padded > kMaxCountedSpan; levels += kMaxCountedSpan, padded -= kMaxCountedSpan) {
    count += count_span_at_or_below(levels, kMaxCountedSpan, l);
  }
  return count + count_span_at_or_below(levels, padded, l);
}

// The largest of v[0..count) (count >= 1), in four independent running maxima: one
// chain of compares waited on each compare before it, a fifth of a decode.
double max_of(const double* v, int count) {
  std::array<double, 4> m = {v[0], v[0], v[0], v[0]};
  int i = 0;
  for (; i + 4 <= count; i += 4) {
    for (std::size_t k = 0; k < 4; ++k) m[k] = std::max(m[k], v[i + static_cast<int>(k)]);
  }
  for (; i < count; ++i) m[0] = std::max(m[0], v[i]);
  return std::max(std::max(m[0], m[1]), std::max(m[2], m[3]));
}

// The smallest grey level L with more than `rank` of the levels at or below it, by
// bisection over L with a count per step (sixteen levels per compare): no histogram to
// clear and scan, and few branches. `levels` holds `count` levels rounded down, padded
// with 255 to a multiple of sixteen (padding never counts: L stays below 255).
int level_of_rank(const std::uint8_t* levels, int count, int rank) {
  const int padded = (count + 15) & ~15;
  int lo = 0, hi = 255;  // every level is at or below 255: more than any rank
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    if (count_at_or_below(levels, padded, mid) > rank) {
      hi = mid;
    } else {
      lo = mid + 1;
    }
  }
  return lo;
}

// The spread between the lo- and hi-quantiles of grey levels (0..255, rounded down).
double quantile_spread(const std::vector<double>& v, double lo, double hi) {
  thread_local std::vector<std::uint8_t> levels;
  const int n = static_cast<int>(v.size());
  levels.assign(static_cast<std::size_t>((n + 15) & ~15), 255);
  for (int i = 0; i < n; ++i) levels[i] = static_cast<std::uint8_t>(std::clamp(v[i], 0.0, 255.0));
  const auto rank_lo = static_cast<int>(lo * (n - 1));
  const auto rank_hi = static_cast<int>(hi * (n - 1));
  return level_of_rank(levels.data(), n, rank_hi) - level_of_rank(levels.data(), n, rank_lo);
}

// Batcher's odd-even merge sort as a list of compare-exchanges, for a fixed size.
template <int N>
struct SortingNetwork {
  std::array<std::pair<int, int>, N * N> pairs{};
  int count = 0;
  constexpr SortingNetwork() {
    for (int p = 1; p < N; p <<= 1) {
      for (int k = p; k >= 1; k >>= 1) {
        for (int j = k % p; j + k < N; j += 2 * k) {
          for (int i = 0; i < std::min(k, N - j - k); ++i) {
            if ((i + j) / (2 * p) == (i + j + k) / (2 * p)) pairs[count++] = {i + j, i + j + k};
          }
        }
      }
    }
  }
};

// The median (the upper one of an even count) of N floats, by a sorting network: min
// and max per step, no branches, where nth_element's insertion sort mispredicted.
template <int N>
float median_of(const float* values) {
  static constexpr SortingNetwork<N> kNetwork;
  std::array<float, N> v;
  std::copy_n(values, N, v.begin());
  for (int c = 0; c < kNetwork.count; ++c) {
    const auto [i, j] = kNetwork.pairs[c];
    const float a = v[i], b = v[j];
    v[i] = std::min(a, b);
    v[j] = std::max(a, b);
  }
  return v[N / 2];
}

// The doubled running integral `c` (unit-width bins centred on whole samples) at
// fractional sample t in [0, 2n): linear between bin boundaries.
double doubled_integral_at(const double* c, double t) {
  const double s = t + 0.5;
  const int k = static_cast<int>(s);
  return c[k] + (s - k) * (c[k + 1] - c[k]);
}

// The on-screen heading, degrees in [0, 360), of the direction at angle a (cos a = c,
// sin a = s) in the unit-circle frame of `shape`: shape · (c, -s), as the samples lie.
double screen_heading_deg(const cv::Matx22d& shape, double c, double s) {
  const double du = shape(0, 0) * c - shape(0, 1) * s, dv = shape(1, 0) * c - shape(1, 1) * s;
  // Within [-180, 180]: one turn added at most (no fmod, as wrap_deg_360 needs).
  double heading_deg = rad_to_deg(fast_atan2(-dv, du));
  if (heading_deg < 0.0) heading_deg += 360.0;
  return heading_deg >= 360.0 ? heading_deg - 360.0 : heading_deg;
}

// t wrapped once into [0, n).
double wrap_samples(double t, double n) {
  while (t < 0.0) t += n;
  while (t >= n) t -= n;
  return t;
}

}  // namespace

Decoder::Decoder(const MarkerFamily& family, const std::vector<int>& ids, DecoderConfig config)
    : config_(config), family_(family), ids_(ids) {
  config_.samples = std::max(24, config_.samples);
  config_.circles = std::clamp(config_.circles, 1, 3);
  track_reach_samples_ = static_cast<int>(std::ceil(kTrackReachDeg * config_.samples / 360.0));
  {
    const auto widths = family.slice_widths_deg();
    const double narrowest = *std::min_element(widths.begin(), widths.end());
    rival_guard_samples_ = static_cast<int>(std::ceil(0.75 * narrowest * config_.samples / 360.0));
  }
  // One circle: the middle of the annulus; two: its inner and outer; three: all.
  constexpr auto& radii = MarkerFamily::sample_radii;
  if (config_.circles == 1) circle_radii_ = {radii[1]};
  if (config_.circles == 2) circle_radii_ = {radii[0], radii[2]};
  if (config_.circles == 3) circle_radii_ = {radii[0], radii[1], radii[2]};
  // Directions of the sampling angles, computed once: the sampler runs per blob per frame.
  sample_directions_ = CircleDirections::make(config_.samples);
  ring_directions_ = CircleDirections::make(kRingSamples, 0.5);
  dense_ring_directions_ = CircleDirections::make(64, 0.25);
  const double n = config_.samples;
  const double deg_per_sample = 360.0 / n;
  for (int id : ids) {
    Ideal ideal;
    ideal.id = id;
    const auto slices = family.slices(id);  // throws for a bad ID
    // Discrete ideal signal on the samples' bins, to compute mean and norm exactly as
    // the correlation sees them.
    std::vector<double> bins(config_.samples, 0.0);
    for (const auto& s : slices) {
      if (!s.white) continue;
      for (int k = 0; k < config_.samples; ++k) {
        // overlap of bin [k-0.5, k+0.5] (in samples) with the slice, handling wrap
        for (double shift : {-n, 0.0, n}) {
          const double a = std::max(k - 0.5, s.start_deg / deg_per_sample + shift);
          const double b = std::min(k + 0.5, s.end_deg / deg_per_sample + shift);
          if (b > a) bins[k] += b - a;
        }
      }
    }
    const double mean = std::accumulate(bins.begin(), bins.end(), 0.0) / n;
    double norm2 = 0.0;
    for (double b : bins) norm2 += (b - mean) * (b - mean);
    const double norm = std::sqrt(norm2);
    for (std::size_t i = 0; i < slices.size(); ++i) {
      const auto& prev = slices[(i + slices.size() - 1) % slices.size()];
      if (prev.white == slices[i].white) continue;
      double e = slices[i].start_deg / deg_per_sample;
      e -= n * std::floor(e / n);
      ideal.edge.push_back(e);
      ideal.step.push_back(((prev.white ? 1.0 : 0.0) - (slices[i].white ? 1.0 : 0.0)) / norm);
      const int index = static_cast<int>(std::floor(e + 0.5));
      ideal.edge_index.push_back(index % config_.samples);
      ideal.edge_frac.push_back(e + 0.5 - index);
    }
    order_knots(ideal);
    ideals_.push_back(std::move(ideal));
    SpotSlices spots;
    for (const auto& sl : slices) {
      const double middle = deg_to_rad(0.5 * (sl.start_deg + sl.end_deg));
      spots.cos.push_back(static_cast<float>(std::cos(middle)));
      spots.sin.push_back(static_cast<float>(std::sin(middle)));
      spots.sign.push_back(sl.white ? 1.0f : -1.0f);
      ++spots.count;
    }
    const std::size_t padded = (slices.size() + 3) & ~std::size_t{3};
    spots.cos.resize(padded, 0.0f);
    spots.sin.resize(padded, 0.0f);
    spot_slices_.push_back(std::move(spots));
  }
  index_of_id_.assign(family.max_id() + 1, -1);
  for (std::size_t i = 0; i < ids.size(); ++i) index_of_id_[ids[i]] = static_cast<int>(i);
  build_key_template(family);
  {
    const auto key = family.slices(family.min_id()).front();
    const double half = deg_to_rad(0.5 * (key.end_deg - key.start_deg));
    key_half_cos_ = std::cos(half);
    key_half_sin_ = std::sin(half);
  }
  decode_by_bits_ = static_cast<int>(ids.size()) > kExhaustiveIds;
}

void Decoder::order_knots(Ideal& ideal) {
  ideal.knot_order.resize(ideal.edge.size());
  std::iota(ideal.knot_order.begin(), ideal.knot_order.end(), 0);
  std::stable_sort(ideal.knot_order.begin(), ideal.knot_order.end(),
                   [&](int a, int b) { return ideal.edge_frac[a] > ideal.edge_frac[b]; });
}

void Decoder::build_key_template(const MarkerFamily& family) {
  // The slices every ID shares: the white key (+1) between two black guards (-1); the
  // code slices weigh nothing. Its correlation peak is the heading whatever the code.
  const double deg_per_sample = 360.0 / config_.samples;
  const auto slices = family.slices(family.min_id());
  const int k = static_cast<int>(slices.size());
  std::vector<double> level(k, 0.0);
  level[0] = 1.0;
  level[1] = level[k - 1] = -1.0;
  key_ = Ideal{};
  for (int i = 0; i < k; ++i) {
    const double step = level[(i + k - 1) % k] - level[i];
    if (step == 0.0) continue;
    double e = slices[i].start_deg / deg_per_sample;
    e -= config_.samples * std::floor(e / config_.samples);
    const int index = static_cast<int>(std::floor(e + 0.5));
    key_.edge.push_back(e);
    key_.step.push_back(step);
    key_.edge_index.push_back(index % config_.samples);
    key_.edge_frac.push_back(e + 0.5 - index);
  }
  order_knots(key_);
  slice_bounds_.clear();
  for (const auto& s : slices) slice_bounds_.emplace_back(s.start_deg / deg_per_sample, s.end_deg / deg_per_sample);
}

SampledSignal Decoder::sample(const cv::Mat& grey, const Blob& blob) const {
  SampledSignal out;
  sample(grey, blob, out);
  return out;
}

void Decoder::sample(const cv::Mat& grey, const Blob& blob, SampledSignal& out) const {
  out.usable = false;
  out.ring_contrast = out.black_level = out.white_level = 0.0;
  out.values.clear();
  const int n = config_.samples;
  // The whole marker must lie inside the image; then no sample needs a bounds check.
  const double reach = 1.0 / MarkerFamily::black_ring_outer_radius;
  if (!ellipse_inside(grey, blob.u, blob.v, blob.shape, reach)) return;
  // shape maps the unit circle to the dark disc; radii below are in the marker's units.
  thread_local std::vector<float> black, white, circle;
  black.resize(ring_directions_.cos.size());
  white.resize(ring_directions_.cos.size());
  circle.resize(sample_directions_.cos.size());
  // The rings first: black just outside the code, white beyond the dark disc. A blob
  // without them is not decoded at all.
  const double black_r = 0.5 * (MarkerFamily::code_outer_radius + MarkerFamily::black_ring_outer_radius);
  const double white_r = 0.5 * (MarkerFamily::black_ring_outer_radius + 1.0);
  sample_ellipse(grey, blob.u, blob.v, blob.shape, reach * black_r, ring_directions_, black.data());
  sample_ellipse(grey, blob.u, blob.v, blob.shape, reach * white_r, ring_directions_, white.data());
  out.black_level = median_of<kRingSamples>(black.data());
  out.white_level = median_of<kRingSamples>(white.data());
  out.ring_contrast = out.white_level - out.black_level;
  if (out.ring_contrast < config_.min_ring_contrast) return;
  const double mid = 0.5 * (out.black_level + out.white_level);
  const auto bright = std::count_if(white.begin(), white.begin() + kRingSamples, [&](float g) { return g > mid; });
  if (bright < config_.min_white_ring_fraction * kRingSamples) return;

  out.values.assign(n, 0.0);
  for (double r : circle_radii_) {
    sample_ellipse(grey, blob.u, blob.v, blob.shape, reach * r, sample_directions_, circle.data());
    for (int k = 0; k < n; ++k) out.values[k] += circle[k];
  }
  if (circle_radii_.size() > 1) {
    const double inv_circles = 1.0 / static_cast<double>(circle_radii_.size());
    for (double& value : out.values) value *= inv_circles;
  }
  const double spread = quantile_spread(out.values, 0.1, 0.9);
  if (spread < config_.min_code_contrast * out.ring_contrast) return;
  out.usable = true;
}

void Decoder::sample_code(const cv::Mat& grey, const Blob& blob, double black_level, double white_level,
                          SampledSignal& out) const {
  out.usable = false;
  out.black_level = black_level;
  out.white_level = white_level;
  out.ring_contrast = white_level - black_level;
  out.values.clear();
  const int n = config_.samples;
  constexpr double r = MarkerFamily::sample_radii[std::size(MarkerFamily::sample_radii) / 2];
  const double scale = r / MarkerFamily::black_ring_outer_radius;
  // The circle is inside the code annulus, well inside the disc; it must be inside the
  // image with its bilinear neighbours.
  if (!ellipse_inside(grey, blob.u, blob.v, blob.shape, scale)) return;
  thread_local std::vector<float> circle;
  circle.resize(sample_directions_.cos.size());
  sample_ellipse(grey, blob.u, blob.v, blob.shape, scale, sample_directions_, circle.data());
  out.values.assign(circle.begin(), circle.begin() + n);
  // No code-spread test: the caller confirms one ID by its score, which a signal
  // without the code's spread cannot reach.
  if (out.ring_contrast < config_.min_ring_contrast) return;
  out.usable = true;
}

double Decoder::integral_at(const Prepared& p, double t) const {
  return doubled_integral_at(p.doubled_cumulative.data(), wrap_samples(t, config_.samples));
}

double Decoder::correlate(const Prepared& p, const Ideal& ideal, double lag) const {
  // The lag into [0, n) once; then every edge + lag lies in [0, 2n) and reads the doubled
  // running integral directly (no wrapping per edge).
  lag = wrap_samples(lag, config_.samples);
  double acc = 0.0;
  for (std::size_t e = 0; e < ideal.edge.size(); ++e) {
    acc += ideal.step[e] * doubled_integral_at(p.doubled_cumulative.data(), ideal.edge[e] + lag);
  }
  return acc;
}

double Decoder::heading_on_screen(const Blob& blob, double lag) const {
  // Polynomial trigonometry (core/fast_trig.hpp): this runs for every decoded marker,
  // and the library's took a tenth of a tracked marker's time.
  double s = 0.0, c = 0.0;
  fast_sincos(2.0 * kPi * lag / config_.samples, s, c);
  return screen_heading_deg(blob.shape, c, s);
}

void Decoder::prepare(const SampledSignal& signal, Prepared& p) const {
  const int n = config_.samples;
  const double* x = signal.values.data();
  // The running integral is periodic because the signal is mean-free; doubling it lets
  // correlate() read any edge + lag in [0, 2n) without wrapping.
  // (Two more entries: edge + lag + 0.5 < 2n + 0.5 reads up to index 2n + 1.)
  // (And a few more for local_peak's window, which reads whole lags past 2n.)
  const int tail = 2 + kLocalWindowPad;
  p.doubled_cumulative.resize(2 * n + tail);
  double* c = p.doubled_cumulative.data();
  double mean = 0.0, norm2 = 0.0;
  int k = 0;
  // Two samples per step. The running integral of a pair [a, b] starting from r is
  // [r, r + a], and r moves on by a + b: one shift, one swap and three adds per pair.
  v_float64x2 sums = cv::v_setzero_f64();
  for (; k + 1 < n; k += 2) sums += cv::v_load(x + k);
  double sum = cv::v_reduce_sum(sums);  // lane 0 + lane 1
  if (k < n) sum += x[k];
  mean = sum / n;
  const v_float64x2 means = cv::v_setall_f64(mean);
  v_float64x2 squares = cv::v_setzero_f64(), running = cv::v_setzero_f64();  // running: r in both lanes
  for (k = 0; k + 1 < n; k += 2) {
    const v_float64x2 centred = cv::v_load(x + k) - means;
    squares += centred * centred;
    const v_float64x2 before = running + cv::v_rotate_left<1>(centred);  // [r, r + a]
    cv::v_store(c + k, before);
    cv::v_store(c + k + n, before);
    running += centred + cv::v_reverse(centred);  // a + b in both lanes
  }
  norm2 = cv::v_reduce_sum(squares);
  if (k < n) {  // an odd sample left over
    const double centred = x[k] - mean;
    c[k] = c[k + n] = cv::v_extract_n<0>(running);
    norm2 += centred * centred;
  }
  for (k = 0; k < tail; ++k) c[2 * n + k] = c[k];
  p.norm = std::sqrt(norm2);
  p.mean = mean;
}

void Decoder::prepare_doubled(const SampledSignal& signal, Prepared& p) const {
  // The mean-free signal doubled beside the doubled running integral: coarse_peak reads
  // both at every lag without wrapping.
  const int n = config_.samples;
  p.doubled_signal.resize(2 * n);
  for (int k = 0; k < n; ++k) p.doubled_signal[k] = p.doubled_signal[k + n] = signal.values[k] - p.mean;
}

double Decoder::lag_of_heading(const Blob& blob, double heading_deg) const {
  const double lag = key_angle_of_heading(blob, heading_deg) * config_.samples / (2.0 * kPi);
  return lag < 0.0 ? lag + config_.samples : lag;
}

std::pair<int, double> Decoder::coarse_peak(const Prepared& p, const Ideal& ideal, std::vector<double>& scratch) const {
  const int n = config_.samples;
  const std::size_t edges = ideal.edge.size();
  constexpr std::size_t kMaxEdges = 16;
  if (edges <= kMaxEdges && n % 2 == 0) {
    // Two lags per step, every edge summed in registers and the best kept per lane: one
    // pass, no array of all lags to write, read back and search. The sum per lag is
    // formed in the same order as correlate_all_lags's, and ties go to the lowest lag,
    // as std::max_element's do.
    const double* cs[kMaxEdges];
    const double* xs[kMaxEdges];
    v_float64x2 steps[kMaxEdges], fracs[kMaxEdges];
    for (std::size_t e = 0; e < edges; ++e) {
      cs[e] = &p.doubled_cumulative[ideal.edge_index[e]];  // + lag < 2n: no modulo
      xs[e] = &p.doubled_signal[ideal.edge_index[e]];
      steps[e] = cv::v_setall_f64(ideal.step[e]);
      fracs[e] = cv::v_setall_f64(ideal.edge_frac[e]);
    }
    v_float64x2 best = cv::v_setall_f64(-std::numeric_limits<double>::infinity());
    v_float64x2 best_lag = cv::v_setzero_f64(), lag_pair(0.0, 1.0);
    const v_float64x2 two = cv::v_setall_f64(2.0);
    for (int lag = 0; lag < n; lag += 2) {
      v_float64x2 v = cv::v_setzero_f64();
      for (std::size_t e = 0; e < edges; ++e) {
        v += steps[e] * (cv::v_load(cs[e] + lag) + fracs[e] * cv::v_load(xs[e] + lag));
      }
      const v_float64x2 better = v > best;
      best = cv::v_select(better, v, best);
      best_lag = cv::v_select(better, lag_pair, best_lag);
      lag_pair += two;
    }
    const double even = cv::v_extract_n<0>(best), odd = cv::v_extract_n<1>(best);
    const double even_lag = cv::v_extract_n<0>(best_lag), odd_lag = cv::v_extract_n<1>(best_lag);
    const bool take_odd = odd > even || (odd == even && odd_lag < even_lag);
    return {static_cast<int>(take_odd ? odd_lag : even_lag), take_odd ? odd : even};
  }
  // Many edges (no family has more than 16) or an odd count: every lag into an array.
  correlate_all_lags(p, ideal, scratch);
  const auto best = std::max_element(scratch.begin(), scratch.end());
  return {static_cast<int>(best - scratch.begin()), *best};
}

std::pair<int, double> Decoder::local_peak(const Prepared& p, const Ideal& ideal, int centre_lag, int reach) const {
  const int n = config_.samples;
  const int first = ((centre_lag - reach) % n + n) % n;
  const int count = 2 * reach + 1;
  // Every lag of the window at once, edge by edge: at a whole lag each edge reads the
  // running integral at a fixed fraction into its bin, so lag + 1 is the next entry (no
  // wrap and no fraction per lag, where correlate() computes both for any lag).
  constexpr int kMaxLags = 32;
  const int padded = (count + 1) & ~1;
  const std::size_t last_read = static_cast<std::size_t>(2 * n - 2 + padded);  // edge_index + lag + 1, at most
  if (padded > kMaxLags || last_read >= p.doubled_cumulative.size()) {
    std::pair<int, double> best{centre_lag, -1e300};
    for (int d = 0; d < count; ++d) {
      const int lag = (first + d) % n;
      const double c = correlate(p, ideal, lag);
      if (c > best.second) best = {lag, c};
    }
    return best;
  }
  alignas(16) double values[kMaxLags];
  const double* c = p.doubled_cumulative.data();
  for (int j = 0; j < padded; j += 2) {  // two lags per step
    v_float64x2 v = cv::v_setzero_f64();
    for (std::size_t e = 0; e < ideal.edge.size(); ++e) {
      const double* at = c + ideal.edge_index[e] + first + j;
      const v_float64x2 lo = cv::v_load(at), hi = cv::v_load(at + 1);
      const v_float64x2 in_bin = lo + cv::v_setall_f64(ideal.edge_frac[e]) * (hi - lo);
      v += cv::v_setall_f64(ideal.step[e]) * in_bin;
    }
    cv::v_store_aligned(values + j, v);
  }
  // The first of equal values wins, as in a scan from the window's low end.
  int best = 0;
  for (int d = 1; d < count; ++d) {
    if (values[d] > values[best]) best = d;
  }
  return {(first + best) % n, values[best]};
}

std::pair<double, double> Decoder::refine_peak(const Prepared& p, const Ideal& ideal, int lag, double value) const {
  // The running integral is linear between bin boundaries, so the correlation (a sum of
  // it at each edge plus the lag) is piecewise linear in the lag, with corners where an
  // edge crosses a bin boundary. Its maximum on [lag - 1, lag + 1] is at one of those
  // corners or an end. Going up from lag - 1 the corners come in an order fixed per
  // ideal (knot_order, then the same again one sample later), and at each the slope
  // changes by one edge's term: one walk finds every corner's value, in time linear in
  // the edges (evaluating each corner afresh was quadratic).
  const int n = config_.samples;
  const std::size_t edges = ideal.edge.size();
  const double lo = lag - 1.0, hi = lag + 1.0;
  double best_lag = lag, best = value;
  auto consider = [&](double t, double c) {
    if (c > best) {
      best = c;
      best_lag = t;
    }
  };
  const double* c = p.doubled_cumulative.data();  // 2n + 2 entries
  const int lo_bin = ((lag - 1) % n + n) % n;
  constexpr std::size_t kMaxEdges = 64;
  if (edges > kMaxEdges) {  // no family has this many; evaluate every corner afresh
    consider(lo, correlate(p, ideal, lo));
    consider(hi, correlate(p, ideal, hi));
    for (double edge : ideal.edge) {
      for (double t = std::ceil(lo + edge + 0.5) - edge - 0.5; t <= hi; t += 1.0) consider(t, correlate(p, ideal, t));
    }
    return {best_lag, best};
  }
  // Per edge, the bin its running integral is read in just above lo, and the slope.
  std::array<int, kMaxEdges> bin;
  double slope = 0.0;
  for (std::size_t e = 0; e < edges; ++e) {
    bin[e] = ideal.edge_index[e] + lo_bin;  // < 2n - 1: two steps up stay inside
    slope += ideal.step[e] * (c[bin[e] + 1] - c[bin[e]]);
  }
  double f = correlate(p, ideal, lo), t_prev = lo;
  consider(lo, f);
  for (int whole = 0; whole < 2; ++whole) {
    for (int e : ideal.knot_order) {
      // The boundary lies (1 - edge_frac) above a whole lag, in (0, 1].
      const double t = lo + whole + (1.0 - ideal.edge_frac[e]);
      if (t >= hi) continue;
      f += slope * (t - t_prev);
      t_prev = t;
      consider(t, f);
      const int k = bin[e]++;
      slope += ideal.step[e] * ((c[k + 2] - c[k + 1]) - (c[k + 1] - c[k]));
    }
  }
  consider(hi, f + slope * (hi - t_prev));
  return {best_lag, best};
}

std::vector<CodeMatch> Decoder::match_all(const SampledSignal& signal, const Blob& blob) const {
  std::vector<CodeMatch> out;
  match_all(signal, blob, out);
  return out;
}

void Decoder::match_all(const SampledSignal& signal, const Blob& blob, std::vector<CodeMatch>& out) const {
  out.clear();
  if (!signal.usable || signal.values.size() != static_cast<std::size_t>(config_.samples)) {
    for (const auto& ideal : ideals_) out.push_back({ideal.id, -1.0, 0.0});
    return;
  }
  // Per-thread scratch: the decoder is shared and immutable, and a frame decodes many
  // blobs, so the buffers are reused instead of allocated per blob.
  thread_local Prepared p;
  prepare(signal, p);
  if (p.norm <= 0.0) {
    for (const auto& ideal : ideals_) out.push_back({ideal.id, -1.0, 0.0});
    return;
  }
  prepare_doubled(signal, p);
  if (decode_by_bits_) {
    match_by_key(p, blob, out);
    return;
  }
  // Each ID at every lag (a few edges per lag: cheap for a handful of IDs): its peak, and
  // its best away from that peak's main lobe, so that a marker two key-slice positions
  // explain almost equally well shows as such (CodeMatch::rival_score). Sharing one lag
  // found from the key and guards alone would hide that: under heavy blur the key's own
  // peak may sit where a different ID's code fits better than the true one's.
  thread_local std::vector<double> scratch;
  thread_local std::vector<std::array<double, 3>> peaks;  // lag, value, rival value
  peaks.clear();
  const int n = config_.samples;
  double family_best = -1e300;
  for (const Ideal& ideal : ideals_) {
    correlate_all_lags(p, ideal, scratch);
    // The peak (its first lag, as std::max_element gives), and the best lag more than
    // rival_guard_samples_ from it round the circle: the lags best + guard + 1 ...
    // best - guard - 1 (mod n), at most two runs.
    const double peak = max_of(scratch.data(), n);
    const int best = static_cast<int>(std::find(scratch.begin(), scratch.end(), peak) - scratch.begin());
    double rival = -1e300;
    const int first = best + rival_guard_samples_ + 1, last = best + n - rival_guard_samples_ - 1;  // inclusive
    if (first <= last) {
      const int end_first_run = std::min(last, n - 1);
      if (first <= end_first_run) rival = max_of(&scratch[static_cast<std::size_t>(first)], end_first_run - first + 1);
      const int a = std::max(first, n) - n, b = last - n;  // the part past n, wrapped
      if (a <= b) rival = std::max(rival, max_of(&scratch[static_cast<std::size_t>(a)], b - a + 1));
    }
    peaks.push_back({static_cast<double>(best), scratch[static_cast<std::size_t>(best)], rival});
    family_best = std::max(family_best, scratch[static_cast<std::size_t>(best)]);
  }
  // Fine pass only for IDs that could win.
  constexpr double kRefineMargin = 0.1;
  for (std::size_t i = 0; i < ideals_.size(); ++i) {
    double lag = peaks[i][0], value = peaks[i][1];
    if ((family_best - value) / p.norm < kRefineMargin) {
      std::tie(lag, value) = refine_peak(p, ideals_[i], static_cast<int>(peaks[i][0]), value);
    }
    out.push_back({ideals_[i].id, std::clamp(value / p.norm, -1.0, 1.0), heading_on_screen(blob, lag),
                   2.0 * kPi * lag / n, std::clamp(peaks[i][2] / p.norm, -1.0, 1.0)});
  }
}

bool Decoder::levels_agree(const cv::Mat& grey, const Blob& blob, const SampledSignal& signal,
                           const CodeMatch& match) const {
  const int n = static_cast<int>(signal.values.size());
  const double contrast = signal.white_level - signal.black_level;
  if (n == 0 || contrast <= 0.0) return false;
  // The code's colour at each sample (the middle of the annulus; sample k lies at angle
  // 2 pi k / n in the shape's unit-circle frame, the key's bisector at key_angle_rad),
  // and whether it lies clear of the slice's edges (blur mixes the colours there).
  constexpr double kMiddle = MarkerFamily::sample_radii[1];
  const double key_deg = match.key_angle_rad * 180.0 / kPi;
  const int clear = std::max(1, n / 24);  // 15 degrees
  thread_local std::vector<double> colour;
  colour.resize(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k)
    colour[static_cast<std::size_t>(k)] = family_.colour_at(match.id, kMiddle, 360.0 * k / n - key_deg);
  // white_before[i]: white samples among the first i of the colours read twice round, so
  // that a window's count is a difference (a modulo per read cost more than the rest).
  thread_local std::vector<int> white_before;
  white_before.assign(static_cast<std::size_t>(3 * n + 1), 0);
  for (int round = 0, i = 0; round < 3; ++round) {
    for (int k = 0; k < n; ++k, ++i) {
      white_before[static_cast<std::size_t>(i + 1)] =
          white_before[static_cast<std::size_t>(i)] + (colour[static_cast<std::size_t>(k)] != 0.0 ? 1 : 0);
    }
  }
  double key_sum = 0.0, black_sum = 0.0;
  int key_count = 0, black_count = 0;
  for (int k = 0; k < n; ++k) {
    // (x - 360 round(x / 360) is std::remainder's value here, at a fraction of its cost.)
    const double x = 360.0 * k / n - key_deg;
    const double off_key = std::abs(x - 360.0 * std::nearbyint(x / 360.0));
    if (off_key < 25.0) {  // well inside the key (the narrowest key, 6UCP's, is 85 degrees)
      key_sum += signal.values[static_cast<std::size_t>(k)];
      ++key_count;
    }
    if (colour[static_cast<std::size_t>(k)] != 0.0) continue;
    // Black from k - clear to k + clear: no white sample in that window (around the circle).
    const int first = k - clear + n;  // index into the doubled counts, >= 0
    if (white_before[static_cast<std::size_t>(first + 2 * clear + 1)] ==
        white_before[static_cast<std::size_t>(first)]) {
      black_sum += signal.values[static_cast<std::size_t>(k)];
      ++black_count;
    }
  }
  if (key_count == 0 || black_count == 0) return false;
  if (signal.white_level - key_sum / key_count > config_.max_key_shortfall * contrast) return false;
  if (black_sum / black_count - signal.black_level > config_.max_black_excess * contrast) return false;
  // The same code on the annulus's inner and outer circles, each read on its own.
  const double reach = 1.0 / MarkerFamily::black_ring_outer_radius;
  thread_local std::vector<float> circle;
  circle.resize(sample_directions_.cos.size());
  const std::vector<double>& ideal = colour;  // the code at the annulus's middle, as above
  double ideal_mean = 0.0;
  for (int k = 0; k < n; ++k) ideal_mean += ideal[static_cast<std::size_t>(k)];
  ideal_mean /= n;
  for (const double r : {MarkerFamily::sample_radii[0], MarkerFamily::sample_radii[2]}) {
    if (static_cast<int>(sample_directions_.count) != n) break;  // a signal of another length: not ours to check
    sample_ellipse(grey, blob.u, blob.v, blob.shape, reach * r, sample_directions_, circle.data());
    double mean = 0.0;
    for (int k = 0; k < n; ++k) mean += circle[static_cast<std::size_t>(k)];
    mean /= n;
    double sxy = 0.0, sxx = 0.0, syy = 0.0;
    for (int k = 0; k < n; ++k) {
      const double x = circle[static_cast<std::size_t>(k)] - mean, y = ideal[static_cast<std::size_t>(k)] - ideal_mean;
      sxy += x * y;
      sxx += x * x;
      syy += y * y;
    }
    if (sxx <= 0.0 || syy <= 0.0 || sxy / std::sqrt(sxx * syy) < config_.min_radial_agreement) return false;
  }
  // The white ring unbroken: nothing lies across the marker.
  if (!white_ring_unbroken(grey, blob, signal.black_level, signal.white_level)) return false;
  // The hole: a small circle half way out to its edge (within the image: the whole marker is).
  thread_local std::vector<float> hole;
  hole.resize(ring_directions_.cos.size());
  sample_ellipse(grey, blob.u, blob.v, blob.shape, reach * 0.5 * MarkerFamily::hole_radius, ring_directions_,
                 hole.data());
  double hole_sum = 0.0;
  for (int k = 0; k < kRingSamples; ++k) hole_sum += hole[static_cast<std::size_t>(k)];
  return hole_sum / kRingSamples - signal.black_level <= config_.max_hole_excess * contrast;
}

bool Decoder::white_ring_unbroken(const cv::Mat& grey, const Blob& blob, double black_level, double white_level) const {
  const double reach = 1.0 / MarkerFamily::black_ring_outer_radius;
  thread_local std::vector<float> ring;
  ring.resize(dense_ring_directions_.cos.size());
  sample_ellipse(grey, blob.u, blob.v, blob.shape, reach * 0.5 * (MarkerFamily::black_ring_outer_radius + 1.0),
                 dense_ring_directions_, ring.data());
  const double mid = 0.5 * (black_level + white_level);
  int dark_reads = 0;
  for (int k = 0; k < dense_ring_directions_.count; ++k) dark_reads += ring[static_cast<std::size_t>(k)] <= mid;
  return dark_reads <= config_.max_dark_white_ring_reads;
}

void Decoder::correlate_all_lags(const Prepared& p, const Ideal& ideal, std::vector<double>& out) const {
  const int n = config_.samples;
  out.assign(static_cast<std::size_t>(n), 0.0);
  // Edge by edge over all lags: contiguous loops the compiler vectorises.
  for (std::size_t e = 0; e < ideal.edge.size(); ++e) {
    const double* c = &p.doubled_cumulative[ideal.edge_index[e]];  // + lag < 2n: no modulo
    const double* x = &p.doubled_signal[ideal.edge_index[e]];
    const double step = ideal.step[e], frac = ideal.edge_frac[e];
    for (int lag = 0; lag < n; ++lag) out[static_cast<std::size_t>(lag)] += step * (c[lag] + frac * x[lag]);
  }
}

void Decoder::match_by_key(const Prepared& p, const Blob& blob, std::vector<CodeMatch>& out) const {
  // Heading first, from the key and guards alone; then the code bits read at that
  // heading; then the exact cross-covariance for the code read and for every code one
  // bit away (the only IDs a misread bit can hide). The cost no longer grows with the
  // number of IDs.
  out.clear();
  for (const auto& ideal : ideals_) out.push_back({ideal.id, -1.0, 0.0});
  thread_local std::vector<double> scratch;
  const auto [key_lag, key_value] = coarse_peak(p, key_, scratch);
  const double lag = refine_peak(p, key_, key_lag, key_value).first;
  auto mean_over = [&](std::size_t slice) {
    const auto [a, b] = slice_bounds_[slice];
    return (integral_at(p, b + lag) - integral_at(p, a + lag)) / (b - a);
  };
  const std::size_t k = slice_bounds_.size();
  const double white = mean_over(0), black = 0.5 * (mean_over(1) + mean_over(k - 1));
  const double mid = 0.5 * (white + black);
  int code = 0;
  for (std::size_t i = 2; i + 1 < k; ++i) {
    if (mean_over(i) > mid) code |= 1 << (i - 2);
  }
  // A bit whose slice reads close to the midpoint may be misread: the code with it
  // flipped is scored too. Clear bits need no second opinion, so a clean marker costs
  // one exact score instead of one per bit.
  std::array<int, 32> candidates{};
  int count = 0;
  candidates[count++] = code;
  const double ambiguous = kAmbiguousBit * std::abs(white - black);
  for (std::size_t i = 2; i + 1 < k && count < static_cast<int>(candidates.size()); ++i) {
    if (std::abs(mean_over(i) - mid) < ambiguous) candidates[count++] = code ^ (1 << (i - 2));
  }
  // The candidates share the key with the template, so their peaks lie where its does:
  // each is refined around the key's whole-sample lag.
  const int n = config_.samples;
  const int centre = (static_cast<int>(lag + 0.5) % n + n) % n;
  for (int i = 0; i < count; ++i) {
    const int id = candidates[i] + 1;
    if (id >= static_cast<int>(index_of_id_.size()) || index_of_id_[id] < 0) continue;
    const Ideal& ideal = ideals_[index_of_id_[id]];
    const auto [fine_lag, value] = refine_peak(p, ideal, centre, correlate(p, ideal, centre));
    out[index_of_id_[id]] = {ideal.id, std::clamp(value / p.norm, -1.0, 1.0), heading_on_screen(blob, fine_lag),
                             2.0 * kPi * fine_lag / n};
  }
}

CodeMatch Decoder::match_one(const SampledSignal& signal, const Blob& blob, int id,
                             std::optional<double> expected_heading_deg) const {
  const int index = id >= 0 && id < static_cast<int>(index_of_id_.size()) ? index_of_id_[id] : -1;
  if (index < 0) throw std::invalid_argument("ID " + std::to_string(id) + " is not decoded here");
  const Ideal& ideal = ideals_[index];
  if (!signal.usable || signal.values.size() != static_cast<std::size_t>(config_.samples)) return {id, -1.0, 0.0};
  thread_local Prepared p;
  prepare(signal, p);
  if (p.norm <= 0.0) return {id, -1.0, 0.0};
  std::pair<int, double> peak{-1, 0.0};
  if (expected_heading_deg) {
    const int n = config_.samples;
    const int centre = static_cast<int>(std::lround(lag_of_heading(blob, *expected_heading_deg))) % n;
    const int reach = track_reach_samples_;
    // The lags next to the expected one first, then uphill one lag at a time while the
    // peak lies on the edge of what has been scored. The correlation falls on both sides
    // of a marker's peak for as far as its narrowest slice (5.7 samples of 60 for 9UCP,
    // 9 for 6UCP), beyond the reach, so the climb stops at the window's best; a marker
    // that turned a little costs three lags instead of the whole window.
    peak = local_peak(p, ideal, centre, 1);
    int offset = ((peak.first - centre) % n + n + n / 2) % n - n / 2;
    while (offset != 0 && std::abs(offset) < reach) {
      const int next = ((centre + offset + (offset > 0 ? 1 : -1)) % n + n) % n;
      const auto beyond = local_peak(p, ideal, next, 0);
      if (!(beyond.second > peak.second)) break;
      peak = beyond;
      offset += offset > 0 ? 1 : -1;
    }
    if (std::abs(offset) >= reach) peak.first = -1;  // on the edge: it may lie beyond
  }
  if (peak.first < 0) {
    prepare_doubled(signal, p);
    thread_local std::vector<double> scratch;
    peak = coarse_peak(p, ideal, scratch);
  }
  const auto [lag, value] = refine_peak(p, ideal, peak.first, peak.second);
  return {id, std::clamp(value / p.norm, -1.0, 1.0), heading_on_screen(blob, lag), 2.0 * kPi * lag / config_.samples};
}

double Decoder::key_angle_of_heading(const Blob& blob, double heading_deg) const {
  const cv::Matx22d& s = blob.shape;
  double he_s = 0.0, he_c = 0.0;
  fast_sincos(deg_to_rad(heading_deg), he_s, he_c);
  const double ex = s(1, 1) * he_c + s(0, 1) * he_s, ey = -s(1, 0) * he_c - s(0, 0) * he_s;  // det S^-1 (c, -s)
  return fast_atan2(-ey, ex);
}

std::optional<SpotCheck> Decoder::spot_check(const cv::Mat& grey, const Blob& blob, int id,
                                             double expected_key_angle_rad, double black_level,
                                             double white_level) const {
  const int index = id >= 0 && id < static_cast<int>(index_of_id_.size()) ? index_of_id_[id] : -1;
  if (index < 0) throw std::invalid_argument("ID " + std::to_string(id) + " is not decoded here");
  const double contrast = white_level - black_level;
  if (!(contrast >= config_.min_ring_contrast)) return std::nullopt;
  const double mid = 0.5 * (black_level + white_level), inv_contrast = 1.0 / contrast;
  // The edges are read on two circles across the code annulus (its inner and outer
  // sampling radii, in units of the dark disc's radius), which halves their noise; the
  // slices' colours on the middle one.
  constexpr double kUnit = 1.0 / MarkerFamily::black_ring_outer_radius;
  constexpr double kInner = MarkerFamily::sample_radii[0] * kUnit, kOuter = MarkerFamily::sample_radii[2] * kUnit;
  constexpr double kMiddle = MarkerFamily::sample_radii[1] * kUnit;
  if (!ellipse_inside(grey, blob.u, blob.v, blob.shape, kOuter)) return std::nullopt;
  const cv::Matx22d& s = blob.shape;
  const double det = s(0, 0) * s(1, 1) - s(0, 1) * s(1, 0);
  if (!(det > 0.0)) return std::nullopt;

  const double expected = expected_key_angle_rad;

  // The balance of the key's edges on a grid of bisectors around the expected one:
  // grey just inside its counter-clockwise edge minus just inside its clockwise edge.
  // It is positive while the bisector lies clockwise of the true one (the first read is
  // still in the white key, the second already in the black guard), crosses zero on it,
  // and is negative beyond. The grid's steps (0.6 px along the circles, but 4.5 degrees
  // at least and half of kTrackReachDeg at most: under a pixel for markers up to 70 px
  // across) are finer than the edges' blur, so it changes sign between two neighbours,
  // where it is close to linear. The grid reaches two steps either way of the turn the
  // track predicts, 9 to 15 degrees (beyond it, the caller correlates); the three
  // bisectors in the middle are read first (a turn as predicted crosses there), the
  // outer two only when it does not. Each group's reads are independent: the four-wide
  // sampler takes them in one go.
  constexpr int kHalfGrid = 2, kGrid = 2 * kHalfGrid + 1;
  const double radius_px = std::sqrt(det);
  const double step =
      std::clamp(0.6 / (0.5 * (kInner + kOuter) * radius_px), deg_to_rad(4.5), deg_to_rad(kTrackReachDeg) / kHalfGrid);
  double grid_c[kGrid], grid_s[kGrid];
  fast_sincos(expected, grid_s[kHalfGrid], grid_c[kHalfGrid]);
  {
    // The step as a rotation (a short series: step < 0.14 rad, to better than 1e-12).
    const double step2 = step * step;
    const double ss = step * (1.0 - step2 / 6.0 * (1.0 - step2 / 20.0 * (1.0 - step2 / 42.0)));
    const double sc = 1.0 - step2 / 2.0 * (1.0 - step2 / 12.0 * (1.0 - step2 / 30.0 * (1.0 - step2 / 56.0)));
    for (int j = kHalfGrid + 1; j < kGrid; ++j) {
      grid_c[j] = grid_c[j - 1] * sc - grid_s[j - 1] * ss;
      grid_s[j] = grid_s[j - 1] * sc + grid_c[j - 1] * ss;
    }
    for (int j = kHalfGrid - 1; j >= 0; --j) {
      grid_c[j] = grid_c[j + 1] * sc + grid_s[j + 1] * ss;
      grid_s[j] = grid_s[j + 1] * sc - grid_c[j + 1] * ss;
    }
  }
  auto grid_angle = [&](int j) { return expected + (j - kHalfGrid) * step; };
  double balance[kGrid], edges[kGrid];
  // Reads both edges of the bisectors `js` on both circles, in one sampler call (4 per
  // bisector: a multiple of four for any count).
  auto read_bisectors = [&](std::initializer_list<int> js) {
    constexpr int kMaxReads = 4 * kGrid;
    alignas(16) float dx[kMaxReads], dy[kMaxReads], level[kMaxReads];
    const int count = static_cast<int>(js.size());
    const double kc = key_half_cos_, ks = key_half_sin_;
    int k = 0;
    for (const int j : js) {
      const double gc = grid_c[j], gs = grid_s[j];
      const double ccw_x = gc * kc - gs * ks, ccw_y = -(gs * kc + gc * ks);  // bisector + half the key
      const double cw_x = gc * kc + gs * ks, cw_y = -(gs * kc - gc * ks);    // bisector - half the key
      dx[k] = static_cast<float>(kInner * ccw_x), dy[k] = static_cast<float>(kInner * ccw_y);
      dx[count + k] = static_cast<float>(kInner * cw_x), dy[count + k] = static_cast<float>(kInner * cw_y);
      dx[2 * count + k] = static_cast<float>(kOuter * ccw_x), dy[2 * count + k] = static_cast<float>(kOuter * ccw_y);
      dx[3 * count + k] = static_cast<float>(kOuter * cw_x), dy[3 * count + k] = static_cast<float>(kOuter * cw_y);
      ++k;
    }
    sample_ellipse(grey, blob.u, blob.v, s, 1.0, dx, dy, 4 * count, level);
    k = 0;
    for (const int j : js) {
      const double ccw = level[k] + level[2 * count + k], cw = level[count + k] + level[3 * count + k];
      balance[j] = 0.5 * (ccw - cw) * inv_contrast;
      edges[j] = (0.25 * (ccw + cw) - mid) * inv_contrast;  // the two edges' mean level
      ++k;
    }
  };
  // The zero crossing (from positive to negative) nearest the expected bisector.
  auto crossing_between = [&](int j) { return balance[j] > 0.0 && balance[j + 1] <= 0.0; };
  read_bisectors({kHalfGrid - 1, kHalfGrid, kHalfGrid + 1});
  int below = crossing_between(kHalfGrid) ? kHalfGrid : crossing_between(kHalfGrid - 1) ? kHalfGrid - 1 : -1;
  if (below < 0) {
    read_bisectors({0, kGrid - 1});
    below = crossing_between(kHalfGrid + 1) ? kHalfGrid + 1 : crossing_between(0) ? 0 : -1;
  }
  if (below < 0) return std::nullopt;
  const double t = balance[below] / (balance[below] - balance[below + 1]);
  // The balance is zero also where both reads are black or both white (a wrong place):
  // the edges must read near the midpoint there.
  if (std::abs(edges[below] + t * (edges[below + 1] - edges[below])) > kSpotEdgeBand) return std::nullopt;
  // The bisector: the grid's direction below the crossing turned by t steps (a short
  // series: t * step < 0.3 rad, to better than 1e-7).
  const double x = t * step, x2 = x * x;
  const double rs = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0)));
  const double rc = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0));
  const double c = grid_c[below] * rc - grid_s[below] * rs, sn = grid_s[below] * rc + grid_c[below] * rs;

  // Every slice's middle must read its colour.
  const SpotSlices& slices = spot_slices_[index];
  constexpr int kMaxSlices = 32;  // k_ucp allows at most 14 slices
  const int padded = static_cast<int>(slices.cos.size());
  if (padded > kMaxSlices) return std::nullopt;
  alignas(16) float sx[kMaxSlices], sy[kMaxSlices], levels[kMaxSlices];
  // The bisector's direction turned by each slice's angle: (x, y) = (cos, -sin) of the
  // sum, as the sampler's directions.
  const auto fc = static_cast<float>(c), fs = static_cast<float>(sn);
  for (int i = 0; i < padded; ++i) {
    sx[i] = fc * slices.cos[i] - fs * slices.sin[i];
    sy[i] = -(fs * slices.cos[i] + fc * slices.sin[i]);
  }
  sample_ellipse(grey, blob.u, blob.v, s, kMiddle, sx, sy, padded, levels);
  // Each slice's level beyond the midpoint towards its colour (a sign per slice), the
  // least of them against the margin: one branch for all (which slices are white
  // differs from marker to marker, and a branch per slice mispredicted).
  const auto fmid = static_cast<float>(mid);
  float least = std::numeric_limits<float>::max();
  for (int i = 0; i < slices.count; ++i) least = std::min(least, (levels[i] - fmid) * slices.sign[i]);
  if (!(least >= static_cast<float>(kSpotMargin * contrast))) return std::nullopt;
  return SpotCheck{screen_heading_deg(s, c, sn), grid_angle(below) + x};
}

}  // namespace rilbed::vision
