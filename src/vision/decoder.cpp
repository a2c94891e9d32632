#include "vision/decoder.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "core/geometry.hpp"

namespace rilbed::vision {

namespace {

// Bilinear grey level at a sub-pixel position; positions outside give -1.
double bilinear(const cv::Mat& grey, double u, double v) {
  if (u < 0.0 || v < 0.0 || u > grey.cols - 1.001 || v > grey.rows - 1.001) return -1.0;
  const int x = static_cast<int>(u), y = static_cast<int>(v);
  const double fx = u - x, fy = v - y;
  const std::uint8_t* r0 = grey.ptr<std::uint8_t>(y);
  const std::uint8_t* r1 = grey.ptr<std::uint8_t>(y + 1);
  return (r0[x] * (1 - fx) + r0[x + 1] * fx) * (1 - fy) + (r1[x] * (1 - fx) + r1[x + 1] * fx) * fy;
}

// Image position of the marker-frame point at radius r (fraction of the outer radius)
// and angle a (radians, CCW on screen). The blob's shape maps the unit circle onto the
// dark disc, whose radius is black_ring_outer_radius.
cv::Point2d marker_point(const Blob& blob, double r, double a) {
  const double k = r / MarkerFamily::black_ring_outer_radius;
  const cv::Vec2d p(k * std::cos(a), -k * std::sin(a));
  const cv::Vec2d q = blob.shape * p;
  return {blob.u + q[0], blob.v + q[1]};
}

double percentile(std::vector<double> v, double p) {
  const auto k = static_cast<std::size_t>(p * (v.size() - 1));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

// Value at fractional index t of the cumulative integral of a piecewise-constant
// periodic signal with unit-width bins centred on integers (cumulative[0] = 0 at
// t = -0.5, cumulative[k+1] = sum of bins 0..k).
double cumulative_at(const std::vector<double>& cumulative, double t) {
  const int n = static_cast<int>(cumulative.size()) - 1;
  const double total = cumulative[n];
  double s = t + 0.5;
  const double wraps = std::floor(s / n);
  s -= wraps * n;
  int k = static_cast<int>(s);
  if (k >= n) k = n - 1;
  const double frac = s - k;
  return wraps * total + cumulative[k] + frac * (cumulative[k + 1] - cumulative[k]);
}

}  // namespace

Decoder::Decoder(const MarkerFamily& family, const std::vector<int>& ids, DecoderConfig config)
    : config_(config), ids_(ids) {
  config_.samples = std::max(24, config_.samples);
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
      ideal.start.push_back(s.start_deg / deg_per_sample);
      ideal.level.push_back(s.white ? 1.0 : 0.0);
      for (int k = 0; k < config_.samples; ++k) {
        // overlap of bin [k-0.5, k+0.5] (in samples) with the slice, handling wrap
        for (double shift : {-n, 0.0, n}) {
          const double a = std::max(k - 0.5, s.start_deg / deg_per_sample + shift);
          const double b = std::min(k + 0.5, s.end_deg / deg_per_sample + shift);
          if (b > a && s.white) bins[k] += b - a;
        }
      }
    }
    const double mean = std::accumulate(bins.begin(), bins.end(), 0.0) / n;
    double norm2 = 0.0;
    for (double b : bins) norm2 += (b - mean) * (b - mean);
    const double norm = std::sqrt(norm2);
    for (double& l : ideal.level) l = (l - mean) / norm;
    ideals_.push_back(std::move(ideal));
  }
}

SampledSignal Decoder::sample(const cv::Mat& grey, const Blob& blob) const {
  SampledSignal out;
  const int n = config_.samples;
  out.values.resize(n);
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * kPi * k / n;
    double sum = 0.0;
    for (double r : MarkerFamily::sample_radii) {
      const cv::Point2d p = marker_point(blob, r, a);
      const double g = bilinear(grey, p.x, p.y);
      if (g < 0.0) return out;  // annulus leaves the image
      sum += g;
    }
    out.values[k] = sum / std::size(MarkerFamily::sample_radii);
  }
  // The rings: black just outside the code, white beyond the dark disc.
  constexpr int kRingSamples = 24;
  const double black_r = 0.5 * (MarkerFamily::code_outer_radius + MarkerFamily::black_ring_outer_radius);
  const double white_r = 0.5 * (MarkerFamily::black_ring_outer_radius + 1.0);
  std::vector<double> black(kRingSamples), white(kRingSamples);
  for (int k = 0; k < kRingSamples; ++k) {
    const double a = 2.0 * kPi * (k + 0.5) / kRingSamples;
    const cv::Point2d pb = marker_point(blob, black_r, a), pw = marker_point(blob, white_r, a);
    black[k] = bilinear(grey, pb.x, pb.y);
    white[k] = bilinear(grey, pw.x, pw.y);
    if (black[k] < 0.0 || white[k] < 0.0) return out;
  }
  const double black_level = percentile(black, 0.5);
  const double white_level = percentile(white, 0.5);
  out.ring_contrast = white_level - black_level;
  if (out.ring_contrast < config_.min_ring_contrast) return out;
  const double mid = 0.5 * (black_level + white_level);
  const auto bright = std::count_if(white.begin(), white.end(), [&](double g) { return g > mid; });
  if (bright < config_.min_white_ring_fraction * kRingSamples) return out;
  const double spread = percentile(out.values, 0.9) - percentile(out.values, 0.1);
  if (spread < config_.min_code_contrast * out.ring_contrast) return out;
  out.usable = true;
  return out;
}

double Decoder::correlate(const std::vector<double>& cumulative, const Ideal& ideal, double lag) const {
  // sum_k x[k] * y[k - lag]: the ideal is piecewise constant, so each segment
  // contributes its level times the integral of x over the shifted segment.
  const double n = config_.samples;
  double acc = 0.0;
  const std::size_t segments = ideal.start.size();
  for (std::size_t s = 0; s < segments; ++s) {
    const double a = ideal.start[s] + lag;
    const double b = (s + 1 < segments ? ideal.start[s + 1] : ideal.start[0] + n) + lag;
    acc += ideal.level[s] * (cumulative_at(cumulative, b) - cumulative_at(cumulative, a));
  }
  return acc;
}

double Decoder::heading_on_screen(const Blob& blob, double lag) const {
  const double a = 2.0 * kPi * lag / config_.samples;
  const cv::Vec2d dir = blob.shape * cv::Vec2d(std::cos(a), -std::sin(a));
  return wrap_deg_360(rad_to_deg(std::atan2(-dir[1], dir[0])));
}

std::vector<CodeMatch> Decoder::match_all(const SampledSignal& signal, const Blob& blob) const {
  std::vector<CodeMatch> out;
  out.reserve(ideals_.size());
  if (!signal.usable) {
    for (const auto& ideal : ideals_) out.push_back({ideal.id, -1.0, 0.0});
    return out;
  }
  const int n = config_.samples;
  const double mean = std::accumulate(signal.values.begin(), signal.values.end(), 0.0) / n;
  double norm2 = 0.0;
  std::vector<double> cumulative(n + 1, 0.0);
  for (int k = 0; k < n; ++k) {
    const double x = signal.values[k] - mean;
    norm2 += x * x;
    cumulative[k + 1] = cumulative[k] + x;
  }
  const double norm = std::sqrt(norm2);
  for (const auto& ideal : ideals_) {
    int best_lag = 0;
    double best = -1e300;
    for (int lag = 0; lag < n; ++lag) {
      const double c = correlate(cumulative, ideal, lag);
      if (c > best) {
        best = c;
        best_lag = lag;
      }
    }
    // Refine the lag below one sample: golden-section search of the (unimodal near its
    // peak) correlation on [best_lag - 1, best_lag + 1].
    double lo = best_lag - 1.0, hi = best_lag + 1.0;
    constexpr double kInvPhi = 0.6180339887498949;
    double m1 = hi - kInvPhi * (hi - lo), m2 = lo + kInvPhi * (hi - lo);
    double c1 = correlate(cumulative, ideal, m1), c2 = correlate(cumulative, ideal, m2);
    for (int it = 0; it < 18; ++it) {
      if (c1 < c2) {
        lo = m1; m1 = m2; c1 = c2;
        m2 = lo + kInvPhi * (hi - lo);
        c2 = correlate(cumulative, ideal, m2);
      } else {
        hi = m2; m2 = m1; c2 = c1;
        m1 = hi - kInvPhi * (hi - lo);
        c1 = correlate(cumulative, ideal, m1);
      }
    }
    const double lag = 0.5 * (lo + hi);
    const double peak = std::max({best, c1, c2});
    out.push_back({ideal.id, norm > 0.0 ? std::clamp(peak / norm, -1.0, 1.0) : -1.0, heading_on_screen(blob, lag)});
  }
  return out;
}

}  // namespace rilbed::vision
