#include "vision/marker_template.hpp"

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "vision/circle_sampler.hpp"

namespace rilbed::vision {
namespace {

constexpr double kPi = 3.14159265358979323846;
// The polar grid, radii as fractions of the outer radius R: the hole, the coded annulus,
// the black ring and the white ring, each a few times (and clear of the floor beyond R).
constexpr std::array<double, 13> kRadii = {0.05, 0.1, 0.2, 0.27, 0.35, 0.43, 0.5, 0.6, 0.665, 0.72, 0.83, 0.9, 0.96};
constexpr int kAngles = 64;
static_assert(std::tuple_size_v<decltype(MarkerTemplates::Model::prefix_sum)> == kRadii.size() + 1);
// Blur strengths, Gaussian sigma as a fraction of R: from a sharp 64 px marker to a
// 20 px one under 2 px of blur and some smear.
constexpr std::array<double, 7> kBlurOfRadius = {0.02, 0.05, 0.08, 0.11, 0.15, 0.2, 0.26};
// The rendered model: R in pixels, and the image's side.
constexpr double kModelRadiusPx = 50.0;
constexpr int kModelSide = 2 * 64 + 1;

// At least the circles up to the white ring's inner half (0.83 R) must lie in the image.
constexpr std::size_t kLeastCircles = 11;
// The black ring's circles (0.6, 0.665 and 0.72 R) and the sector its misfit is summed
// over: 4 of the 64 angles, 22.5 degrees, about a cable's width on a 24 px marker.
constexpr std::size_t kFirstBlackCircle = 7, kBlackCircles = 3;
constexpr int kSectorAngles = 4;
static_assert(kRadii[kFirstBlackCircle] > MarkerFamily::code_outer_radius &&
              kRadii[kFirstBlackCircle + kBlackCircles - 1] < MarkerFamily::black_ring_outer_radius);

// The least-squares fit of `levels` (centred, unit norm) by the first levels.size()
// values of `model`: levels ~ gain * (model - mean).
struct LinearFit {
  double correlation = -1.0;
  double gain = 0.0, mean = 0.0;
};
LinearFit fit_levels(const std::vector<float>& levels, const MarkerTemplates::Model& model) {
  const std::size_t n = levels.size();
  const std::size_t circles = n / kAngles;
  // The model's sums over those circles were taken when it was rendered; only the dot
  // product is left, a circle (64 floats) at a time in vector lanes, the circles summed
  // in double. This ran for every blob that reached the template, 7 models each.
  static_assert(kAngles % 16 == 0);
  const double sum = model.prefix_sum[circles], sum_sq = model.prefix_sum_sq[circles];
  double dot = 0.0;
  for (std::size_t c = 0; c < circles; ++c) {
    const float* l = levels.data() + c * kAngles;
    const float* m = model.levels.data() + c * kAngles;
    cv::v_float32x4 acc0 = cv::v_setzero_f32(), acc1 = cv::v_setzero_f32();
    for (int k = 0; k < kAngles; k += 8) {
      acc0 = cv::v_fma(cv::v_load(l + k), cv::v_load(m + k), acc0);
      acc1 = cv::v_fma(cv::v_load(l + k + 4), cv::v_load(m + k + 4), acc1);
    }
    dot += cv::v_reduce_sum(acc0 + acc1);
  }
  const double var = sum_sq - sum * sum / static_cast<double>(n);
  if (var <= 1e-12) return {};
  // levels sum to 0: the model's mean drops out of dot.
  return {dot / std::sqrt(var), dot / var, sum / static_cast<double>(n)};
}

// The worst sector's mean residual energy per sample on the black ring's circles, over
// the fitted model's mean energy per sample across the whole grid (the correlation
// squared over the samples: the levels have unit norm). Measured against the whole
// marker's contrast, not the ring's own, which a heavily blurred model leaves near zero.
double black_ring_misfit(const std::vector<float>& levels, const std::vector<float>& model, const LinearFit& fit) {
  std::array<double, kAngles> residual{};
  for (std::size_t c = kFirstBlackCircle; c < kFirstBlackCircle + kBlackCircles; ++c) {
    for (int k = 0; k < kAngles; ++k) {
      const std::size_t i = c * kAngles + static_cast<std::size_t>(k);
      const double r = levels[i] - fit.gain * (model[i] - fit.mean);
      residual[static_cast<std::size_t>(k)] += r * r;
    }
  }
  const double signal_per_sample = fit.correlation * fit.correlation / static_cast<double>(levels.size());
  if (signal_per_sample <= 1e-12) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (int k = 0; k < kAngles; ++k) {
    double r = 0.0;
    for (int j = 0; j < kSectorAngles; ++j) r += residual[static_cast<std::size_t>((k + j) % kAngles)];
    worst = std::max(worst, r / (kSectorAngles * kBlackCircles) / signal_per_sample);
  }
  return worst;
}

// Centres `values` and scales them to unit norm; false when they are all alike. (Four
// running sums each: one chain of dependent additions left the CPU waiting on every add.)
bool normalise(std::vector<float>& values) {
  const std::size_t n = values.size(), n4 = n & ~std::size_t{3};
  std::array<double, 4> sums{};
  for (std::size_t i = 0; i < n4; i += 4) {
    for (std::size_t j = 0; j < 4; ++j) sums[j] += values[i + j];
  }
  for (std::size_t i = n4; i < n; ++i) sums[0] += values[i];
  const double mean = (sums[0] + sums[1] + sums[2] + sums[3]) / static_cast<double>(n);
  std::array<double, 4> norms{};
  for (std::size_t i = 0; i < n4; i += 4) {
    for (std::size_t j = 0; j < 4; ++j) {
      values[i + j] = static_cast<float>(values[i + j] - mean);
      norms[j] += static_cast<double>(values[i + j]) * values[i + j];
    }
  }
  for (std::size_t i = n4; i < n; ++i) {
    values[i] = static_cast<float>(values[i] - mean);
    norms[0] += static_cast<double>(values[i]) * values[i];
  }
  const double norm = norms[0] + norms[1] + norms[2] + norms[3];
  if (norm <= 1e-12) return false;
  const auto scale = static_cast<float>(1.0 / std::sqrt(norm));
  for (float& v : values) v *= scale;
  return true;
}

// The marker drawn large and sharp, the key's bisector pointing right (+u); white 1.
cv::Mat render(const MarkerFamily& family, int id) {
  cv::Mat image(kModelSide, kModelSide, CV_32F);
  const double c = (kModelSide - 1) / 2.0;
  for (int y = 0; y < kModelSide; ++y) {
    for (int x = 0; x < kModelSide; ++x) {
      const double dx = x - c, dy = y - c;
      const double r = std::hypot(dx, dy) / kModelRadiusPx;
      const double angle_deg = std::atan2(-dy, dx) * 180.0 / kPi;  // counter-clockwise on screen
      const double colour = family.colour_at(id, r, angle_deg);
      image.at<float>(y, x) = static_cast<float>(colour < 0.0 ? 1.0 : colour);  // beyond R: the white ring's
    }
  }
  return image;
}

// The model's levels on the polar grid (bilinear), radius-major.
std::vector<float> sample_polar(const cv::Mat& model) {
  std::vector<float> out;
  out.reserve(kRadii.size() * kAngles);
  const double c = (kModelSide - 1) / 2.0;
  for (double r : kRadii) {
    for (int k = 0; k < kAngles; ++k) {
      const double a = 2.0 * kPi * k / kAngles;
      const float x = static_cast<float>(c + r * kModelRadiusPx * std::cos(a));
      const float y = static_cast<float>(c - r * kModelRadiusPx * std::sin(a));
      cv::Mat px;
      cv::getRectSubPix(model, cv::Size(1, 1), cv::Point2f(x, y), px);
      out.push_back(px.at<float>(0, 0));
    }
  }
  return out;
}

}  // namespace

MarkerTemplates::MarkerTemplates(const MarkerFamily& family, const std::vector<int>& ids, MarkerTemplateConfig config)
    : family_(family), config_(config), ids_(ids), models_(ids.size()) {}

const MarkerTemplates::Models& MarkerTemplates::models_of(std::size_t index) const {
  Models& blurred = models_[index];
  if (!blurred.empty()) return blurred;
  const cv::Mat sharp = render(family_, ids_[index]);
  for (double blur : kBlurOfRadius) {
    cv::Mat image;
    cv::GaussianBlur(sharp, image, cv::Size(), blur * kModelRadiusPx, 0.0, cv::BORDER_REPLICATE);
    Model model;
    model.levels = sample_polar(image);
    // Running sums over whole circles, in the order a plain loop over the levels takes.
    double sum = 0.0, sum_sq = 0.0;
    for (std::size_t c = 0; c < kRadii.size(); ++c) {
      for (int k = 0; k < kAngles; ++k) {
        const float v = model.levels[c * kAngles + static_cast<std::size_t>(k)];
        sum += v;
        sum_sq += static_cast<double>(v) * v;
      }
      model.prefix_sum[c + 1] = sum;
      model.prefix_sum_sq[c + 1] = sum_sq;
    }
    blurred.push_back(std::move(model));
  }
  return blurred;
}

TemplateFit MarkerTemplates::fit(const cv::Mat& grey, const Blob& blob, int id, double key_angle_rad) const {
  const auto which = std::find(ids_.begin(), ids_.end(), id);
  if (which == ids_.end()) return {};
  // The shape turned so that direction 0 of the circle reads the key's bisector:
  // (cos(key + b), -sin(key + b)) = [[c, s], [-s, c]] (cos b, -sin b).
  const double c = std::cos(key_angle_rad), s = std::sin(key_angle_rad);
  const cv::Matx22d shape = blob.shape * cv::Matx22d(c, s, -s, c);
  const double to_disc = 1.0 / MarkerFamily::black_ring_outer_radius;  // the shape maps the unit circle to the disc
  // The circles that lie inside the image: a marker at the frame's edge may lose the
  // outer part of its white ring, but not the rings within.
  std::size_t circles = 0;
  // (Checked on the blob's own shape: the same ellipse, and turning the shape would only
  // loosen ellipse_inside's box.)
  while (circles < kRadii.size() && ellipse_inside(grey, blob.u, blob.v, blob.shape, kRadii[circles] * to_disc)) {
    ++circles;
  }
  if (circles < kLeastCircles) return {};
  static const CircleDirections directions = CircleDirections::make(kAngles);
  thread_local std::vector<float> circle, levels;
  circle.resize(directions.cos.size());
  levels.clear();
  for (std::size_t i = 0; i < circles; ++i) {
    sample_ellipse(grey, blob.u, blob.v, shape, kRadii[i] * to_disc, directions, circle.data());
    levels.insert(levels.end(), circle.begin(), circle.begin() + kAngles);
  }
  if (!normalise(levels)) return {};
  LinearFit best;
  const std::vector<float>* best_model = nullptr;
  for (const Model& model : models_of(static_cast<std::size_t>(which - ids_.begin()))) {
    const LinearFit f = fit_levels(levels, model);
    if (f.correlation > best.correlation) {
      best = f;
      best_model = &model.levels;
    }
  }
  if (best_model == nullptr) return {};
  return {best.correlation, black_ring_misfit(levels, *best_model, best)};
}

}  // namespace rilbed::vision
