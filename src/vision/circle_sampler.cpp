#include "vision/circle_sampler.hpp"

#include <bit>
#include <cmath>
#include <cstdint>

#include <opencv2/core/hal/intrin.hpp>

#include "core/geometry.hpp"

namespace rilbed::vision {

CircleDirections CircleDirections::make(int count, double phase) {
  CircleDirections d;
  d.count = count;
  const int padded = (count + 3) & ~3;
  // Padding directions are zero: they read the centre, which is inside the image.
  d.cos.assign(padded, 0.0f);
  d.sin.assign(padded, 0.0f);
  for (int k = 0; k < count; ++k) {
    const double a = 2.0 * kPi * (k + phase) / count;
    d.cos[k] = static_cast<float>(std::cos(a));
    d.sin[k] = static_cast<float>(-std::sin(a));
  }
  return d;
}

void sample_ellipse(const cv::Mat& grey, double centre_u, double centre_v, const cv::Matx22d& shape, double radius,
                    const CircleDirections& directions, float* out) {
  sample_ellipse(grey, centre_u, centre_v, shape, radius, directions.cos.data(), directions.sin.data(),
                 static_cast<int>(directions.cos.size()), out);
}

void sample_ellipse(const cv::Mat& grey, double centre_u, double centre_v, const cv::Matx22d& shape, double radius,
                    const float* direction_x, const float* direction_y, int count, float* out) {
  const std::uint8_t* data = grey.ptr<std::uint8_t>(0);
  const std::ptrdiff_t stride = static_cast<std::ptrdiff_t>(grey.step[0]);
  const auto a = static_cast<float>(shape(0, 0) * radius), b = static_cast<float>(shape(0, 1) * radius);
  const auto c = static_cast<float>(shape(1, 0) * radius), d = static_cast<float>(shape(1, 1) * radius);
  const auto cu = static_cast<float>(centre_u), cv = static_cast<float>(centre_v);
  // Four points per step, written once with OpenCV's universal intrinsics (SSE2 on x86,
  // NEON on ARM, OpenCV's C++ emulation elsewhere): their coordinates, whole and
  // fractional parts in vector lanes; the pixel reads are scalar (SSE2 has no gather),
  // two neighbours per 16-bit read, and the interpolation is in vector lanes again.
  using cv::v_float32x4;
  using cv::v_int32x4;
  using cv::v_uint16x8;
  using cv::v_uint32x4;
  const v_float32x4 va = cv::v_setall_f32(a), vb = cv::v_setall_f32(b), vc = cv::v_setall_f32(c),
                    vd = cv::v_setall_f32(d);
  const v_float32x4 vcu = cv::v_setall_f32(cu), vcv = cv::v_setall_f32(cv);
  // Byte offsets of the points' top-left pixels, y * stride + x, formed in float (exact
  // below 2^24 bytes, checked below) and converted once: SSE2 has no 32-bit multiply.
  const bool offsets_in_float = static_cast<double>(grey.rows) * static_cast<double>(stride) < 16777216.0;
  const v_float32x4 vstride = cv::v_setall_f32(static_cast<float>(stride));
  alignas(16) int offsets[4], xs[4], ys[4];
  // p[0] | p[1] << 8 of a pixel and its right neighbour (one 16-bit read).
  auto pair = [](const std::uint8_t* p) { return static_cast<std::uint16_t>(p[0] | p[1] << 8); };
  const v_uint32x4 low_byte = cv::v_setall_u32(0xFF);
  // The choice of offsets is a template parameter: no test per step.
  auto sample_all = [&]<bool kOffsetsInFloat>() {
    for (int k = 0; k < count; k += 4) {
      const v_float32x4 dx = cv::v_load(direction_x + k), dy = cv::v_load(direction_y + k);
      const v_float32x4 u = vcu + (va * dx + vb * dy);
      const v_float32x4 v = vcv + (vc * dx + vd * dy);
      const v_int32x4 ui = cv::v_trunc(u), vi = cv::v_trunc(v);  // floor: coordinates are positive
      const v_float32x4 uf = cv::v_cvt_f32(ui), vf = cv::v_cvt_f32(vi);
      const v_float32x4 fx = u - uf, fy = v - vf;
      const std::uint8_t *p0, *p1, *p2, *p3;
      if constexpr (kOffsetsInFloat) {
        cv::v_store_aligned(offsets, cv::v_trunc(vf * vstride + uf));
        p0 = data + offsets[0], p1 = data + offsets[1], p2 = data + offsets[2], p3 = data + offsets[3];
      } else {
        cv::v_store_aligned(xs, ui);
        cv::v_store_aligned(ys, vi);
        p0 = data + static_cast<std::ptrdiff_t>(ys[0]) * stride + xs[0];
        p1 = data + static_cast<std::ptrdiff_t>(ys[1]) * stride + xs[1];
        p2 = data + static_cast<std::ptrdiff_t>(ys[2]) * stride + xs[2];
        p3 = data + static_cast<std::ptrdiff_t>(ys[3]) * stride + xs[3];
      }
      // Each point's pair on its row and the pair below in one 32-bit lane (16-bit lanes
      // filled from memory), then the four pixels apart: bytes 0 to 3 of the lane, low
      // to high on a little-endian CPU.
      static_assert(std::endian::native == std::endian::little, "two 16-bit lanes read as one 32-bit lane");
      const v_uint32x4 quads =
          cv::v_reinterpret_as_u32(v_uint16x8(pair(p0), pair(p0 + stride), pair(p1), pair(p1 + stride), pair(p2),
                                              pair(p2 + stride), pair(p3), pair(p3 + stride)));
      auto to_float = [](const v_uint32x4& x) { return cv::v_cvt_f32(cv::v_reinterpret_as_s32(x)); };
      const v_float32x4 a00 = to_float(quads & low_byte), a01 = to_float((quads >> 8) & low_byte);
      const v_float32x4 a10 = to_float((quads >> 16) & low_byte), a11 = to_float(quads >> 24);
      const v_float32x4 top = a00 + (a01 - a00) * fx;
      const v_float32x4 bottom = a10 + (a11 - a10) * fx;
      cv::v_store(out + k, top + (bottom - top) * fy);
    }
  };
  if (offsets_in_float) {
    sample_all.template operator()<true>();
  } else {
    sample_all.template operator()<false>();
  }
}

}  // namespace rilbed::vision
