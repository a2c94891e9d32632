#include "vision/occluder.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <vector>

#include "vision/circle_sampler.hpp"
#include "vision/marker_family.hpp"

namespace rilbed::vision {
namespace {

constexpr int kReads = 64;
// Radii as fractions of the marker's outer radius: the white ring's middle, and two
// circles on the floor beyond it (clear of the ring's blurred edge).
constexpr double kRingRadius = 0.5 * (MarkerFamily::black_ring_outer_radius + 1.0);
constexpr std::array<double, 2> kFloorRadii = {1.15, 1.3};

const CircleDirections& directions() {
  static const CircleDirections d = CircleDirections::make(kReads);
  return d;
}

// The value at `fraction` of the way up `reads` sorted (which it reorders).
double level_at(std::span<float> reads, double fraction) {
  const auto k = static_cast<std::size_t>(fraction * static_cast<double>(reads.size() - 1) + 0.5);
  std::nth_element(reads.begin(), reads.begin() + static_cast<std::ptrdiff_t>(k), reads.end());
  return reads[k];
}

}  // namespace

BandAcross find_band_across(const cv::Mat& grey, const Blob& blob, double black_level, double white_level,
                            const OccluderConfig& config) {
  BandAcross out;
  const double contrast = white_level - black_level;
  // The shape maps the unit circle to the dark disc; the marker's radius is larger.
  const double to_marker = 1.0 / MarkerFamily::black_ring_outer_radius;
  if (!config.enabled || contrast <= 0 ||
      !ellipse_inside(grey, blob.u, blob.v, blob.shape, kFloorRadii.back() * to_marker)) {
    return out;
  }
  const CircleDirections& d = directions();
  // Per-thread scratch, as the decoder's: a frame checks every named marker, and four
  // vectors allocated per marker cost more than the reads themselves.
  thread_local std::vector<float> ring, floor_reads, scratch, sorted;
  for (auto* v : {&ring, &floor_reads, &scratch}) v->resize(d.cos.size());
  sample_ellipse(grey, blob.u, blob.v, blob.shape, kRingRadius * to_marker, d, ring.data());
  // The floor: of the two circles, the read further from the floor's level at each angle
  // (a cable is a band across both; a thin one may fall between reads of one circle).
  sample_ellipse(grey, blob.u, blob.v, blob.shape, kFloorRadii[0] * to_marker, d, floor_reads.data());
  sample_ellipse(grey, blob.u, blob.v, blob.shape, kFloorRadii[1] * to_marker, d, scratch.data());
  sorted.assign(floor_reads.begin(), floor_reads.begin() + kReads);
  sorted.insert(sorted.end(), scratch.begin(), scratch.begin() + kReads);
  const double floor_level = level_at(sorted, 0.5);
  sorted.assign(ring.begin(), ring.begin() + kReads);
  const double ring_level = level_at(sorted, 0.75);
  std::array<bool, kReads> floor_off{}, ring_dim{};
  for (int k = 0; k < kReads; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const double off = std::max(std::abs(floor_reads[i] - floor_level), std::abs(scratch[i] - floor_level));
    floor_off[i] = off >= config.floor_dip * contrast;
    ring_dim[i] = ring[i] <= ring_level - config.ring_dip * contrast;
  }
  // The length of the run of floor reads off the floor's level through each read (0
  // where it is not off; kReads where the whole circle is).
  std::array<int, kReads> floor_run{};
  for (int k = 0; k < kReads; ++k) {
    if (!floor_off[static_cast<std::size_t>(k)] || floor_run[static_cast<std::size_t>(k)] != 0) continue;
    int first = k, last = k;
    while (last - first + 1 < kReads && floor_off[static_cast<std::size_t>((last + 1) % kReads)]) ++last;
    while (last - first + 1 < kReads && floor_off[static_cast<std::size_t>((first - 1 + kReads) % kReads)]) --first;
    for (int j = first; j <= last; ++j)
      floor_run[static_cast<std::size_t>((j % kReads + kReads) % kReads)] = last - first + 1;
  }
  // Runs of dim ring reads round the circle, from a read that is not dim (if any).
  int start = 0;
  while (start < kReads && ring_dim[static_cast<std::size_t>(start)]) ++start;
  if (start == kReads) return out;  // dim all round: no band, a dim ring (levels_agree's to judge)
  for (int n = 0; n < kReads;) {
    const int k = (start + n) % kReads;
    if (!ring_dim[static_cast<std::size_t>(k)]) {
      ++n;
      continue;
    }
    int length = 0;
    while (n < kReads && ring_dim[static_cast<std::size_t>((start + n) % kReads)]) ++length, ++n;
    if (length < config.min_band_reads || length > config.max_band_reads) continue;
    bool beyond = false;
    for (int j = -config.max_shift_reads; j < length + config.max_shift_reads && !beyond; ++j) {
      const auto q = static_cast<std::size_t>(((k + j) % kReads + kReads) % kReads);
      beyond = floor_off[q] && floor_run[q] <= config.max_floor_run_reads;
    }
    if (!beyond) continue;
    ++out.bands;
  }
  out.across = out.bands >= std::max(1, config.min_bands);
  return out;
}

}  // namespace rilbed::vision
