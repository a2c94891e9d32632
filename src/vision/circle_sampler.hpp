// Bilinear grey levels at many points of an ellipse in an 8-bit image, four at a time:
// the decoder's sampling of a marker's code circle and rings, which is most of a full
// decode's pixel work.
#pragma once

#include <opencv2/core.hpp>

#include <cmath>
#include <vector>

namespace rilbed::vision {

/// Unit directions around a circle, kept as separate float arrays (what the four-wide
/// sampler reads), padded to a multiple of four.
struct CircleDirections {
  std::vector<float> cos, sin;
  int count = 0;  ///< directions in use (the arrays may be longer)
  /// `count` directions at angles 2π(k + phase)/count, k = 0..count-1, counter-clockwise
  /// on screen (v down): (cos a, -sin a).
  static CircleDirections make(int count, double phase = 0.0);
};

/// Half-width and half-height, pixels, of the box around the ellipse
/// centre + radius · shape · (unit circle) (shape as Blob::shape).
/// (Inline: every tracked marker asks several times per frame.)
inline cv::Vec2d ellipse_half_extent(const cv::Matx22d& shape, double radius) {
  return {radius * (std::abs(shape(0, 0)) + std::abs(shape(0, 1))),
          radius * (std::abs(shape(1, 0)) + std::abs(shape(1, 1)))};
}

/// True when the box around that ellipse, widened by `margin_px`, lies inside the image
/// together with the right and lower neighbours a bilinear read takes: the check
/// sample_ellipse() leaves to its caller.
inline bool ellipse_inside(const cv::Mat& grey, double centre_u, double centre_v, const cv::Matx22d& shape,
                           double radius, double margin_px = 0.0) {
  const cv::Vec2d half = ellipse_half_extent(shape, radius) + cv::Vec2d(margin_px, margin_px);
  return centre_u - half[0] >= 0.0 && centre_v - half[1] >= 0.0 && centre_u + half[0] < grey.cols - 1.0 &&
         centre_v + half[1] < grey.rows - 1.0;
}

/// Writes to `out[k]` the bilinear grey level at centre + radius · M · d_k, where M maps
/// the unit circle onto the ellipse (as Blob::shape) and d_k are the directions. The
/// caller guarantees that every point and its right and lower neighbours are inside the
/// image (no check here). `out` must hold directions.cos.size() floats.
void sample_ellipse(const cv::Mat& grey, double centre_u, double centre_v, const cv::Matx22d& shape, double radius,
                    const CircleDirections& directions, float* out);

/// The same for `count` directions given as two arrays (x = cos a, y = -sin a, as
/// CircleDirections holds them); `count` must be a multiple of four (pad with zeros,
/// which read the centre).
void sample_ellipse(const cv::Mat& grey, double centre_u, double centre_v, const cv::Matx22d& shape, double radius,
                    const float* direction_x, const float* direction_y, int count, float* out);

}  // namespace rilbed::vision
