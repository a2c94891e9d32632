#include "vision/disc_edge_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <utility>

#include <opencv2/core/hal/intrin.hpp>

#include "core/geometry.hpp"
#include "vision/circle_sampler.hpp"
#include "vision/marker_family.hpp"

namespace rilbed::vision {

namespace {

// Radii of the middle of the black ring and of the white ring, in units of the dark
// disc's radius (the disc's outline is 1).
constexpr double kBlackMid = 0.5 * (MarkerFamily::code_outer_radius + MarkerFamily::black_ring_outer_radius) /
                             MarkerFamily::black_ring_outer_radius;
constexpr double kWhiteMid =
    0.5 * (1.0 + MarkerFamily::black_ring_outer_radius) / MarkerFamily::black_ring_outer_radius;
constexpr int kMaxLines = 32;
constexpr int kMaxPoints = 4 * kMaxLines;

// Walks along a line of pixels (a row or a column) from pixel `start` towards the
// outside (`step` bytes per pixel outwards: the stride, negative inwards) to find where
// the grey level crosses `threshold` from the dark disc to the bright ring; at most
// `reach` pixels either way from `start`. `bright_from` is the least whole grey level at
// or above the threshold (so a pixel is dark when below it: integer compares in the
// loop). Sets `offset` to the crossing's distance from `start` in pixels, outwards
// (sub-pixel, linear between the two pixels around it); false when there is none.
// Inline, with the pixels around the crossing kept from the walk's own reads.
inline bool walk_to_edge(const std::uint8_t* start, std::ptrdiff_t step, int reach, double threshold, int bright_from,
                         double& offset) {
  int dark_at = 0, dark = start[0], bright = 0;  // the dark pixel (offset outwards) and the bright one after it
  if (dark < bright_from) {
    // From dark, outwards to the first bright pixel.
    int i = 1;
    for (; i <= reach; ++i) {
      bright = start[i * step];
      if (bright >= bright_from) break;
      dark = bright;
    }
    if (i > reach) return false;
    dark_at = i - 1;
  } else {
    // From bright, inwards to the first dark pixel.
    bright = dark;
    int i = 1;
    for (; i <= reach; ++i) {
      dark = start[-i * step];
      if (dark < bright_from) break;
      bright = dark;
    }
    if (i > reach) return false;
    dark_at = -i;
  }
  // dark < bright_from <= bright, and threshold lies in (dark, bright]: no clamp needed.
  offset = dark_at + (threshold - dark) / (bright - dark);
  return true;
}

// Solves a x = b for a symmetric positive-definite 5x5 `a` (row-major) by Cholesky,
// written out for the fixed size (OpenCV's general routine cost a tenth of a fit).
// False when `a` is not positive definite (the points do not pin down a conic).
bool solve_spd5(const double* a, const double* b, double* x) {
  constexpr int n = 5;
  double l[n][n] = {};
  // Fully unrolled (a fixed size): the loop bookkeeping cost as much as the arithmetic.
#pragma GCC unroll 5
  for (int j = 0; j < n; ++j) {
    double d = a[j * n + j];
#pragma GCC unroll 5
    for (int k = 0; k < j; ++k) d -= l[j][k] * l[j][k];
    if (!(d > 0.0)) return false;
    l[j][j] = std::sqrt(d);
    const double inv = 1.0 / l[j][j];
#pragma GCC unroll 5
    for (int i = j + 1; i < n; ++i) {
      double v = a[i * n + j];
#pragma GCC unroll 5
      for (int k = 0; k < j; ++k) v -= l[i][k] * l[j][k];
      l[i][j] = v * inv;
    }
  }
  double y[n];
#pragma GCC unroll 5
  for (int i = 0; i < n; ++i) {  // L y = b
    double v = b[i];
#pragma GCC unroll 5
    for (int k = 0; k < i; ++k) v -= l[i][k] * y[k];
    y[i] = v / l[i][i];
  }
#pragma GCC unroll 5
  for (int i = n - 1; i >= 0; --i) {  // L^T x = y
    double v = y[i];
#pragma GCC unroll 5
    for (int k = i + 1; k < n; ++k) v -= l[k][i] * x[k];
    x[i] = v / l[i][i];
  }
  return std::isfinite(x[0]);
}

// Symmetric square root of a symmetric positive-definite 2x2 matrix.
cv::Matx22d sqrt_spd(const cv::Matx22d& c) {
  const double s = std::sqrt(c(0, 0) * c(1, 1) - c(0, 1) * c(1, 0));
  const double t = std::sqrt(c(0, 0) + c(1, 1) + 2.0 * s);
  return cv::Matx22d(c(0, 0) + s, c(0, 1), c(1, 0), c(1, 1) + s) * (1.0 / t);
}

// The reads lie in the middle of rings about three pixels wide or more, on a disc that
// just fitted an ellipse closely: a mean is as good as a median here, and cheaper.
double mean_of(const double* values, int count) {
  double sum = 0.0;
  for (int i = 0; i < count; ++i) sum += values[i];
  return sum / count;
}

// The pixels worth loading before fit_disc_edges runs on `predicted`, clipped to the
// image: x0..x1, y0..y1 inclusive; empty when x1 < x0 or y1 < y0. Across, as far as its
// reads go (the white ring's middle beyond the farthest crossing); down, only the rows
// the predicted disc spans. The columns' walks read a pixel or two beyond the outline,
// and those few lines are fetched on demand while other work goes on: a cold frame
// waits for every line loaded up front, and loading the marker's whole height took
// longer than it saved (8-marker tracked frame on flushed frames: 0.0113 ms with rows
// out to the walks' reach, 0.0105 ms with the disc's rows; 3 rows fewer was 0.0116).
struct PixelBox {
  int x0, x1, y0, y1;
  bool empty() const { return x1 < x0 || y1 < y0; }
};

PixelBox disc_area(const cv::Mat& grey, const Blob& predicted, const DiscEdgeFitConfig& config) {
  const double half_w = ellipse_half_extent(predicted.shape, (1.0 + config.reach) * kWhiteMid + 0.05)[0];
  const double half_h = ellipse_half_extent(predicted.shape, 1.0)[1];
  return {std::max(0, static_cast<int>(predicted.u - half_w)),
          std::min(grey.cols - 1, static_cast<int>(predicted.u + half_w) + 1),
          std::max(0, static_cast<int>(predicted.v - half_h)),
          std::min(grey.rows - 1, static_cast<int>(predicted.v + half_h) + 1)};
}

constexpr int kLine = 64;  // bytes per cache line

}  // namespace

std::uint8_t load_disc_area(const cv::Mat& grey, const Blob& predicted, const DiscEdgeFitConfig& config) {
  const PixelBox box = disc_area(grey, predicted, config);
  if (box.empty()) return 0;
  const int x0 = box.x0, x1 = box.x1, y0 = box.y0, y1 = box.y1;
  // One byte per cache line, OR-ed together: independent loads, which the CPU keeps
  // many of in flight at once.
  std::uint8_t any = 0;
  const std::uint8_t* row = grey.ptr<std::uint8_t>(y0);
  const std::size_t stride = grey.step[0];
  if (x1 - x0 < kLine) {
    // A marker up to a line wide (the common case): its two ends cover each row.
    for (int y = y0; y <= y1; ++y, row += stride) any |= row[x0] | row[x1];
    return any;
  }
  for (int y = y0; y <= y1; ++y, row += stride) {
    for (int x = x0 & ~(kLine - 1); x <= x1; x += kLine) any |= row[x];
    any |= row[x1];
  }
  return any;
}

void prefetch_disc_area(const cv::Mat& grey, const Blob& predicted, const DiscEdgeFitConfig& config) {
  const PixelBox box = disc_area(grey, predicted, config);
  if (box.empty()) return;
  const int x0 = box.x0, x1 = box.x1, y0 = box.y0, y1 = box.y1;
  // Locality 1: towards L2. L1 has too few slots for misses and drops most of a burst
  // of several markers' areas; L2 takes them all in time.
  const std::uint8_t* row = grey.ptr<std::uint8_t>(y0);
  const std::size_t stride = grey.step[0];
  if (x1 - x0 < kLine) {
    // A marker up to a line wide (the common case): its two ends cover each row.
    for (int y = y0; y <= y1; ++y, row += stride) {
      __builtin_prefetch(row + x0, 0, 1);
      __builtin_prefetch(row + x1, 0, 1);
    }
    return;
  }
  for (int y = y0; y <= y1; ++y, row += stride) {
    for (int x = x0 & ~(kLine - 1); x <= x1; x += kLine) __builtin_prefetch(row + x, 0, 1);
    __builtin_prefetch(row + x1, 0, 1);
  }
}

namespace {

// The sums over crossings below take two per step in the lanes of OpenCV's universal
// intrinsics (SSE2 on x86, NEON on ARM, OpenCV's C++ emulation elsewhere), written once;
// the lanes are added at the end, and an odd crossing left over is added alone.
using cv::v_float64x2;

// The moments of points up to the fourth order, for one point (T = double) or one per
// lane (T = v_float64x2): one body for both, so that the vector and the tail loop add
// the same terms in the same order.
template <class T>
struct PointMoments {
  T x, y, xx, xy, yy, xxx, xxy, xyy, yyy, xxxx, xxxy, xxyy, xyyy, yyyy;
  explicit PointMoments(T zero)
      : x(zero),
        y(zero),
        xx(zero),
        xy(zero),
        yy(zero),
        xxx(zero),
        xxy(zero),
        xyy(zero),
        yyy(zero),
        xxxx(zero),
        xxxy(zero),
        xxyy(zero),
        xyyy(zero),
        yyyy(zero) {}
  void add(const T& px, const T& py) {
    const T pxx = px * px, pxy = px * py, pyy = py * py;
    x += px;
    y += py;
    xx += pxx;
    xy += pxy;
    yy += pyy;
    xxx += pxx * px;
    xxy += pxx * py;
    xyy += px * pyy;
    yyy += pyy * py;
    xxxx += pxx * pxx;
    xxxy += pxx * pxy;
    xxyy += pxx * pyy;
    xyyy += pxy * pyy;
    yyyy += pyy * pyy;
  }
  // Each moment through `f` (the lanes' sum).
  template <class F>
  PointMoments<double> map(F f) const {
    PointMoments<double> out(0.0);
    out.x = f(x), out.y = f(y), out.xx = f(xx), out.xy = f(xy), out.yy = f(yy);
    out.xxx = f(xxx), out.xxy = f(xxy), out.xyy = f(xyy), out.yyy = f(yyy);
    out.xxxx = f(xxxx), out.xxxy = f(xxxy), out.xxyy = f(xxyy), out.xyyy = f(xyyy), out.yyyy = f(yyyy);
    return out;
  }
};

// Mean square of each crossing's radial distance from the ellipse (p - c)^T m (p - c) = 1,
// as a fraction of its radius there (the same in every linearly related frame).
double residual_rms2(const double* px, const double* py, int found, double x0, double y0, double m00, double m01,
                     double m11) {
  double residual2 = 0.0;
  int first_unpaired = 0;
  {
    // Two crossings per step (a square root each: one instruction for both).
    const v_float64x2 vx0 = cv::v_setall_f64(x0), vy0 = cv::v_setall_f64(y0), vm00 = cv::v_setall_f64(m00),
                      vm01 = cv::v_setall_f64(2.0 * m01), vm11 = cv::v_setall_f64(m11), one = cv::v_setall_f64(1.0);
    v_float64x2 sum = cv::v_setzero_f64();
    for (; first_unpaired + 1 < found; first_unpaired += 2) {
      const v_float64x2 dx = cv::v_load(px + first_unpaired) - vx0;
      const v_float64x2 dy = cv::v_load(py + first_unpaired) - vy0;
      const v_float64x2 form = vm00 * dx * dx + (vm01 * dx * dy + vm11 * dy * dy);
      const v_float64x2 rho = cv::v_sqrt(cv::v_max(form, cv::v_setzero_f64())) - one;
      sum += rho * rho;
    }
    residual2 = cv::v_reduce_sum(sum);
  }
  for (int i = first_unpaired; i < found; ++i) {
    const double dx = px[i] - x0, dy = py[i] - y0;
    const double rho = std::sqrt(std::max(0.0, m00 * dx * dx + 2.0 * m01 * dx * dy + m11 * dy * dy)) - 1.0;
    residual2 += rho * rho;
  }
  return residual2 / found;
}

// The rings' levels and the white ring's bright fraction, from the reads beside the
// crossings.
void set_levels(DiscEdgeFit& fit, const double* black, const double* white, int levels) {
  fit.black_level = mean_of(black, levels);
  fit.white_level = mean_of(white, levels);
  const double mid = 0.5 * (fit.black_level + fit.white_level);
  fit.white_fraction =
      static_cast<double>(std::count_if(white, white + levels, [&](double g) { return g > mid; })) / levels;
}

// The disc as the predicted outline moved and scaled: the crossings p (pixel offsets
// from the predicted centre over the radius) satisfy (p - c)^T Q (p - c) = k, with Q the
// predicted outline's form in those units (p^T Q p = 1 on it). Linear in g = Q c and
// h = k - c^T Q c: p^T Q p = 2 g^T p + h, three unknowns by least squares.
std::optional<DiscEdgeFit> fit_centre_and_size(const Blob& predicted, double threshold_grey,
                                               const DiscEdgeFitConfig& config, double q00, double q01, double q11,
                                               double radius_px, const double* px, const double* py, int found,
                                               const double* black, const double* white, int levels) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0, sz = 0, sxz = 0, syz = 0;
  int first_single = 0;
  {
    // Two crossings per step, one in each lane; the lanes are added at the end.
    const v_float64x2 vq00 = cv::v_setall_f64(q00), vq01 = cv::v_setall_f64(2.0 * q01), vq11 = cv::v_setall_f64(q11);
    v_float64x2 mx = cv::v_setzero_f64(), my = mx, mxx = mx, mxy = mx, myy = mx, mz = mx, mxz = mx, myz = mx;
    for (; first_single + 1 < found; first_single += 2) {
      const v_float64x2 x = cv::v_load(px + first_single), y = cv::v_load(py + first_single);
      const v_float64x2 xx = x * x, xy = x * y, yy = y * y;
      const v_float64x2 z = vq00 * xx + (vq01 * xy + vq11 * yy);
      mx += x;
      my += y;
      mxx += xx;
      mxy += xy;
      myy += yy;
      mz += z;
      mxz += x * z;
      myz += y * z;
    }
    auto lanes = [](const v_float64x2& v) { return cv::v_reduce_sum(v); };
    sx = lanes(mx), sy = lanes(my), sxx = lanes(mxx), sxy = lanes(mxy), syy = lanes(myy);
    sz = lanes(mz), sxz = lanes(mxz), syz = lanes(myz);
  }
  for (int i = first_single; i < found; ++i) {
    const double x = px[i], y = py[i];
    const double z = q00 * x * x + 2.0 * q01 * x * y + q11 * y * y;
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    syy += y * y;
    sz += z;
    sxz += x * z;
    syz += y * z;
  }
  // Normal equations for (2 g_x, 2 g_y, h), solved by Cramer's rule.
  const double n = found;
  const double a00 = sxx, a01 = sxy, a02 = sx, a11 = syy, a12 = sy, a22 = n;
  const double c00 = a11 * a22 - a12 * a12, c01 = a02 * a12 - a01 * a22, c02 = a01 * a12 - a02 * a11;
  const double det = a00 * c00 + a01 * c01 + a02 * c02;
  if (!(std::abs(det) > 1e-12 * n * n * n)) return std::nullopt;
  const double c11 = a00 * a22 - a02 * a02, c12 = a01 * a02 - a00 * a12, c22 = a00 * a11 - a01 * a01;
  const double inv_det = 1.0 / det;
  const double gx2 = (c00 * sxz + c01 * syz + c02 * sz) * inv_det;
  const double gy2 = (c01 * sxz + c11 * syz + c12 * sz) * inv_det;
  const double h = (c02 * sxz + c12 * syz + c22 * sz) * inv_det;
  // c = Q^-1 g; k = h + g^T c.
  const double det_q = q00 * q11 - q01 * q01;
  const double gx = 0.5 * gx2, gy = 0.5 * gy2;
  const double x0 = (q11 * gx - q01 * gy) / det_q, y0 = (q00 * gy - q01 * gx) / det_q;
  const double k = h + gx * x0 + gy * y0;
  if (!(k > 0.0)) return std::nullopt;
  const double inv_k = 1.0 / k;
  // The residual test as fit_from's, with the form Q / k of the fitted outline.
  const double residual2 = residual_rms2(px, py, found, x0, y0, q00 * inv_k, q01 * inv_k, q11 * inv_k);
  // [[unlikely]]: a tracked disc's outline mostly fits, and without the hint GCC takes the
  // success path for cold and calls set_levels instead of inlining it.
  if (residual2 > config.max_residual * config.max_residual) [[unlikely]]
    return std::nullopt;
  // The area scales as k (the outline's radius as sqrt(k)).
  if (std::abs(k - 1.0) > config.max_area_change) return std::nullopt;
  DiscEdgeFit fit;
  const double scale = std::sqrt(k);
  fit.blob.u = predicted.u + radius_px * x0;
  fit.blob.v = predicted.v + radius_px * y0;
  fit.blob.shape = predicted.shape * scale;
  fit.blob.threshold = threshold_grey;
  fit.blob.filled_area_px = kPi * radius_px * radius_px * k;
  fit.residual = std::sqrt(residual2);
  set_levels(fit, black, white, levels);
  return fit;
}

// An ellipse (p - c)^T m (p - c) = 1 in the crossings' frame.
struct Ellipse {
  double x0, y0, m00, m01, m11;
};

// The ellipse closest (algebraically) to the first `count` crossings, or nothing when
// they pin down no ellipse.
std::optional<Ellipse> fit_ellipse(const double* px, const double* py, int count) {
  // The normal equations need only the moments of the points up to the fourth order;
  // summed in named accumulators (a loop over a small phi array made the compiler store
  // and reload it through memory, which stalled on every point). Two points per step,
  // one in each lane, then the odd one out: the same sums for both (PointMoments).
  PointMoments<v_float64x2> pairs(cv::v_setzero_f64());
  int first_single = 0;
  for (; first_single + 1 < count; first_single += 2)
    pairs.add(cv::v_load(px + first_single), cv::v_load(py + first_single));
  PointMoments<double> m = pairs.map([](const v_float64x2& v) { return cv::v_reduce_sum(v); });
  for (int i = first_single; i < count; ++i) m.add(px[i], py[i]);
  const double sx = m.x, sy = m.y, sxx = m.xx, sxy = m.xy, syy = m.yy, sxxx = m.xxx, sxxy = m.xxy, sxyy = m.xyy,
               syyy = m.yyy, sxxxx = m.xxxx, sxxxy = m.xxxy, sxxyy = m.xxyy, sxyyy = m.xyyy, syyyy = m.yyyy;
  // Rows and columns in the order x², xy, y², x, y.
  const double normal_values[25] = {sxxxx, sxxxy, sxxyy, sxxx, sxxy,  //
                                    sxxxy, sxxyy, sxyyy, sxxy, sxyy,  //
                                    sxxyy, sxyyy, syyyy, sxyy, syyy,  //
                                    sxxx,  sxxy,  sxyy,  sxx,  sxy,   //
                                    sxxy,  sxyy,  syyy,  sxy,  syy};
  const double rhs_values[5] = {sxx, sxy, syy, sx, sy};
  double conic[5];
  if (!solve_spd5(normal_values, rhs_values, conic)) return std::nullopt;
  // The conic A x² + B xy + C y² + D x + E y = 1 as (x - x0)^T m (x - x0) = 1.
  const double m00 = conic[0], m01 = 0.5 * conic[1], m11 = conic[2];
  const double det_m = m00 * m11 - m01 * m01;
  if (!(m00 > 0.0 && det_m > 0.0)) return std::nullopt;  // not an ellipse
  const double inv_det_m = 1.0 / det_m;
  const double hx = -0.5 * conic[3], hy = -0.5 * conic[4];
  const double x0 = (m11 * hx - m01 * hy) * inv_det_m, y0 = (m00 * hy - m01 * hx) * inv_det_m;
  const double level = 1.0 + x0 * hx + y0 * hy;  // 1 + x0^T m x0, as m x0 = h
  if (!(level > 0.0)) return std::nullopt;
  const double inv_level = 1.0 / level;
  return Ellipse{x0, y0, m00 * inv_level, m01 * inv_level, m11 * inv_level};
}

// A crossing's radial distance from the ellipse, as a fraction of its radius there.
double radial_residual(double px, double py, const Ellipse& e) {
  const double dx = px - e.x0, dy = py - e.y0;
  return std::sqrt(std::max(0.0, e.m00 * dx * dx + 2.0 * e.m01 * dx * dy + e.m11 * dy * dy)) - 1.0;
}

// The index of the first `count` crossings' farthest inside the ellipse.
int deepest_crossing(const double* px, const double* py, int count, const Ellipse& e) {
  int worst = 0;
  double worst_rho = 1.0;
  for (int i = 0; i < count; ++i) {
    const double rho = radial_residual(px[i], py[i], e);
    if (rho < worst_rho) {
      worst_rho = rho;
      worst = i;
    }
  }
  return worst;
}

// One fit from `predicted`. When too few crossings are found but enough to say where
// the disc lies, `shift_px` (if given) receives the prediction's error, estimated from
// those found.
//
// The crossings are kept as pixel offsets from the predicted centre divided by the
// predicted radius (well conditioned, and one multiply per crossing). The algebraic
// conic fit below is the same in any frame related to that one by a linear map (each
// point's residual is unchanged), and so is the residual test; only the shift estimate
// of a failed fit needs the prediction's unit-circle frame, and maps its few points there.
std::optional<DiscEdgeFit> fit_from(const cv::Mat& grey, const Blob& predicted, double threshold_grey,
                                    const DiscEdgeFitConfig& config, cv::Vec2d* shift_px) {
  const int lines = std::clamp(config.lines, 2, kMaxLines);
  const cv::Matx22d& s = predicted.shape;
  // Every read lies within the white ring's middle of the farthest crossing: check once
  // that all of it is inside the image (with a pixel to spare).
  const double extent = (1.0 + config.reach) * kWhiteMid;
  if (!ellipse_inside(grey, predicted.u, predicted.v, s, extent, 2.0)) return std::nullopt;
  const double det_s = s(0, 0) * s(1, 1) - s(0, 1) * s(1, 0);
  if (!(det_s > 0.0)) return std::nullopt;
  // The predicted outline as a quadratic form: (x - c)^T q (x - c) = 1, q = (S S^T)^-1.
  const double inv_det2 = 1.0 / (det_s * det_s);
  const double q00 = (s(1, 0) * s(1, 0) + s(1, 1) * s(1, 1)) * inv_det2;
  const double q11 = (s(0, 0) * s(0, 0) + s(0, 1) * s(0, 1)) * inv_det2;
  const double q01 = -(s(0, 0) * s(1, 0) + s(0, 1) * s(1, 1)) * inv_det2;
  const double radius_px = std::sqrt(det_s), inv_radius = 1.0 / radius_px;
  const int reach = std::max(2, static_cast<int>(std::ceil(config.reach * radius_px)));
  const int bright_from = static_cast<int>(std::ceil(threshold_grey));
  const std::uint8_t* data = grey.ptr<std::uint8_t>(0);
  const std::ptrdiff_t stride = static_cast<std::ptrdiff_t>(grey.step[0]);
  // Nearest pixel; coordinates are positive here (inside the image), so adding a half
  // and truncating rounds (std::lround is a library call).
  auto nearest = [](double x) { return static_cast<int>(x + 0.5); };
  // The rings' half-widths along a row: at least their radial half-widths (0.15 and 0.14
  // of the radius) anywhere in the middle of the disc.
  const int black_step = std::max(1, nearest((1.0 - kBlackMid) * radius_px));
  const int white_step = std::max(1, nearest((kWhiteMid - 1.0) * radius_px));

  // Crossings (pixel offsets from the predicted centre over the radius); and on the
  // rows, the rings' levels read on the same row (pixels the walk has mostly brought
  // into the cache already).
  alignas(16) double px[kMaxPoints], py[kMaxPoints];
  double black[kMaxPoints], white[kMaxPoints];
  int found = 0, tried = 0, levels = 0;
  // Rows across the middle of the disc find its left and right edges, columns its top
  // and bottom: each crossing is then read where the outline is steep along the line, and
  // along a row or column the pixels are plain bytes (no interpolation). The axis is a
  // template parameter: the loop body has no per-crossing choice between the two.
  const double cu = predicted.u, cv = predicted.v;
  auto cross_lines = [&]<bool kRows>() {
    // Along: the direction of the line (u for a row); across: between lines.
    const double q_along = kRows ? q00 : q11, q_across = kRows ? q11 : q00;
    const double inv_q_along = 1.0 / q_along;
    const double half_span = 1.0 / std::sqrt(q_across - q01 * q01 * inv_q_along);  // the outline's extent across
    const double base_along = kRows ? cu : cv, base_across = kRows ? cv : cu;
    const std::ptrdiff_t step_along = kRows ? 1 : stride, step_across = kRows ? stride : 1;
    double* along_out = kRows ? px : py;
    double* across_out = kRows ? py : px;
    for (int i = 0; i < lines; ++i) {
      // Lines spread over the middle 70% of the extent, where the outline is steep.
      const double d_target = half_span * 0.7 * (2.0 * (i + 0.5) / lines - 1.0);
      const int line = nearest(base_across + d_target);
      const double d = line - base_across;
      const double disc = q01 * q01 * d * d - q_along * (q_across * d * d - 1.0);
      if (disc <= 0.0) continue;
      const double mid = base_along - q01 * d * inv_q_along, half = std::sqrt(disc) * inv_q_along;
      const std::uint8_t* line_start = data + line * step_across;
      const double across = d * inv_radius;
#pragma GCC unroll 2
      for (int side = -1; side <= 1; side += 2) {
        ++tried;
        const int start = nearest(mid + side * half - 0.5 * side);  // the last pixel inside
        double offset = 0.0;
        if (!walk_to_edge(line_start + start * step_along, side * step_along, reach, threshold_grey, bright_from,
                          offset)) {
          continue;
        }
        offset *= side;
        along_out[found] = (start + offset - base_along) * inv_radius;
        across_out[found] = across;
        ++found;
        if constexpr (kRows) {
          const int at = nearest(start + offset);
          black[levels] = line_start[at - side * black_step];
          white[levels] = line_start[at + side * white_step];
          ++levels;
        }
      }
    }
  };
  cross_lines.template operator()<true>();
  cross_lines.template operator()<false>();
  if (found < std::max(6.0, config.min_edge_fraction * tried)) {
    // A disc that moved off the prediction by more than the reach shows its crossings on
    // one side only. Those found still say where it went: in the prediction's
    // unit-circle frame (S^-1 times the pixel offset) each crossing's distance from the
    // unit circle is about the shift's component along its direction, and the shift
    // follows by least squares.
    if (shift_px == nullptr || found < 6) return std::nullopt;
    const cv::Matx22d to_unit = s.inv() * radius_px;
    double a00 = 0, a01 = 0, a11 = 0, b0 = 0, b1 = 0;
    for (int i = 0; i < found; ++i) {
      const cv::Vec2d p = to_unit * cv::Vec2d(px[i], py[i]);
      const double r = std::hypot(p[0], p[1]);
      if (!(r > 0.0)) continue;
      const double ux = p[0] / r, uy = p[1] / r, d = r - 1.0;
      a00 += ux * ux;
      a01 += ux * uy;
      a11 += uy * uy;
      b0 += ux * d;
      b1 += uy * d;
    }
    const double det = a00 * a11 - a01 * a01;
    if (!(det > 1e-6 * found * found)) return std::nullopt;
    const cv::Vec2d t((a11 * b0 - a01 * b1) / det, (a00 * b1 - a01 * b0) / det);
    *shift_px = s * t;
    return std::nullopt;
  }
  if (levels < 4) return std::nullopt;
  if (config.keep_shape) {
    return fit_centre_and_size(predicted, threshold_grey, config, q00 * det_s, q01 * det_s, q11 * det_s, radius_px, px,
                               py, found, black, white, levels);
  }

  // The general ellipse through the crossings; then, while the crossing deepest inside it
  // lies deeper than outlier_residual and fewer than max_outliers have gone, that crossing
  // is dropped and the ellipse fitted again to the rest (something lying across the rim).
  std::optional<Ellipse> e = fit_ellipse(px, py, found);
  if (!e) return std::nullopt;
  int kept = found, outliers = 0;
  double residual2 = residual_rms2(px, py, kept, e->x0, e->y0, e->m00, e->m01, e->m11);
  // (No crossing lies beyond outlier_residual while the squares' sum stays below its square.)
  while (outliers < config.max_outliers && residual2 * kept > config.outlier_residual * config.outlier_residual) {
    const int worst = deepest_crossing(px, py, kept, *e);
    if (radial_residual(px[worst], py[worst], *e) >= -config.outlier_residual) break;
    --kept;
    std::swap(px[worst], px[kept]);
    std::swap(py[worst], py[kept]);
    ++outliers;
    auto refit = fit_ellipse(px, py, kept);
    if (!refit) return std::nullopt;
    e = refit;
    residual2 = residual_rms2(px, py, kept, e->x0, e->y0, e->m00, e->m01, e->m11);
  }
  const double x0 = e->x0, y0 = e->y0, m00 = e->m00, m01 = e->m01, m11 = e->m11;
  const double det_m = m00 * m11 - m01 * m01;

  // residual2: the mean square of each kept crossing's distance from the ellipse,
  // radially, as a fraction of the ellipse's radius there (the same in every linearly
  // related frame).
  if (residual2 > config.max_residual * config.max_residual) [[unlikely]]
    return std::nullopt;  // as above

  // Back to pixels: the outline is centre + radius (x0 + m^-1/2 u), so the shape's
  // square is radius² m^-1.
  const double cov_scale = radius_px * radius_px / det_m;
  const cv::Matx22d cov(m11 * cov_scale, -m01 * cov_scale, -m01 * cov_scale, m00 * cov_scale);
  const double det_c = cov(0, 0) * cov(1, 1) - cov(0, 1) * cov(1, 0);
  if (!(det_c > 0.0)) return std::nullopt;
  const double mean = 0.5 * (cov(0, 0) + cov(1, 1));
  const double diff = std::sqrt(0.25 * (cov(0, 0) - cov(1, 1)) * (cov(0, 0) - cov(1, 1)) + cov(0, 1) * cov(0, 1));
  if (!(mean - diff > 0.0) || std::sqrt((mean + diff) / (mean - diff)) > config.max_axis_ratio) return std::nullopt;
  const double area = kPi * std::sqrt(det_c);
  const double predicted_area = kPi * det_s;
  if (std::abs(area - predicted_area) > config.max_area_change * predicted_area) return std::nullopt;

  DiscEdgeFit fit;
  fit.blob.u = predicted.u + radius_px * x0;
  fit.blob.v = predicted.v + radius_px * y0;
  fit.blob.shape = sqrt_spd(cov);
  fit.blob.threshold = threshold_grey;
  fit.blob.filled_area_px = area;
  fit.residual = std::sqrt(residual2);
  fit.outliers = outliers;
  set_levels(fit, black, white, levels);
  return fit;
}

}  // namespace

std::optional<DiscEdgeFit> fit_disc_edges(const cv::Mat& grey, const Blob& predicted, double threshold_grey,
                                          const DiscEdgeFitConfig& config) {
  CV_Assert(grey.type() == CV_8UC1);
  cv::Vec2d shift(0.0, 0.0);
  if (auto fit = fit_from(grey, predicted, threshold_grey, config, &shift)) return fit;
  // Once more from where the crossings found say the disc went (less than the disc's
  // radius away, or it is not this disc): one more fit costs a tenth of a fill.
  const double moved2 = shift.dot(shift);
  if (!(moved2 > 0.0) || moved2 > cv::determinant(predicted.shape)) return std::nullopt;
  Blob moved = predicted;
  moved.u += shift[0];
  moved.v += shift[1];
  return fit_from(grey, moved, threshold_grey, config, nullptr);
}

}  // namespace rilbed::vision
