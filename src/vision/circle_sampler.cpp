#include "vision/circle_sampler.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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
  const int n = count;
  auto pixel_quad = [&](int x, int y, float fx, float fy) {
    const std::uint8_t* p = data + static_cast<std::ptrdiff_t>(y) * stride + x;
    const float top = p[0] + (p[1] - p[0]) * fx;
    const float bottom = p[stride] + (p[stride + 1] - p[stride]) * fx;
    return top + (bottom - top) * fy;
  };
#if defined(__SSE2__)
  // Four points per step: their coordinates, whole and fractional parts in SSE; the
  // pixel reads are scalar (SSE2 has no gather), two neighbours per 16-bit read, and the
  // interpolation is SSE again.
  const __m128 va = _mm_set1_ps(a), vb = _mm_set1_ps(b), vc = _mm_set1_ps(c), vd = _mm_set1_ps(d);
  const __m128 vcu = _mm_set1_ps(cu), vcv = _mm_set1_ps(cv);
  const __m128i low_byte = _mm_set1_epi32(0xFF);
  // Byte offsets of the points' top-left pixels, y * stride + x, formed in float (exact
  // below 2^24 bytes, checked below) and converted once: SSE2 has no 32-bit multiply.
  const bool offsets_in_float = static_cast<double>(grey.rows) * static_cast<double>(stride) < 16777216.0;
  const __m128 vstride = _mm_set1_ps(static_cast<float>(stride));
  alignas(16) int offsets[4], xs[4], ys[4];
  // p[0] | p[1] << 8 of four pixels into the low halves of four 32-bit lanes, each pair
  // inserted straight from memory (pinsrw), with no round trip through an integer register.
  auto pairs_at = [](const std::uint8_t* p0, const std::uint8_t* p1, const std::uint8_t* p2, const std::uint8_t* p3) {
    auto word = [](const std::uint8_t* p) {
      std::uint16_t w;
      std::memcpy(&w, p, sizeof w);
      return static_cast<int>(w);
    };
    __m128i v = _mm_setzero_si128();
    v = _mm_insert_epi16(v, word(p0), 0);
    v = _mm_insert_epi16(v, word(p1), 2);
    v = _mm_insert_epi16(v, word(p2), 4);
    return _mm_insert_epi16(v, word(p3), 6);
  };
  for (int k = 0; k < n; k += 4) {
    const __m128 dx = _mm_loadu_ps(direction_x + k), dy = _mm_loadu_ps(direction_y + k);
    const __m128 u = _mm_add_ps(vcu, _mm_add_ps(_mm_mul_ps(va, dx), _mm_mul_ps(vb, dy)));
    const __m128 v = _mm_add_ps(vcv, _mm_add_ps(_mm_mul_ps(vc, dx), _mm_mul_ps(vd, dy)));
    const __m128i ui = _mm_cvttps_epi32(u), vi = _mm_cvttps_epi32(v);  // floor: coordinates are positive
    const __m128 uf = _mm_cvtepi32_ps(ui), vf = _mm_cvtepi32_ps(vi);
    const __m128 fx = _mm_sub_ps(u, uf), fy = _mm_sub_ps(v, vf);
    const std::uint8_t *p0, *p1, *p2, *p3;
    if (offsets_in_float) {
      _mm_store_si128(reinterpret_cast<__m128i*>(offsets), _mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(vf, vstride), uf)));
      p0 = data + offsets[0], p1 = data + offsets[1], p2 = data + offsets[2], p3 = data + offsets[3];
    } else {
      _mm_store_si128(reinterpret_cast<__m128i*>(xs), ui);
      _mm_store_si128(reinterpret_cast<__m128i*>(ys), vi);
      p0 = data + static_cast<std::ptrdiff_t>(ys[0]) * stride + xs[0];
      p1 = data + static_cast<std::ptrdiff_t>(ys[1]) * stride + xs[1];
      p2 = data + static_cast<std::ptrdiff_t>(ys[2]) * stride + xs[2];
      p3 = data + static_cast<std::ptrdiff_t>(ys[3]) * stride + xs[3];
    }
    const __m128i upper = pairs_at(p0, p1, p2, p3);
    const __m128i lower = pairs_at(p0 + stride, p1 + stride, p2 + stride, p3 + stride);
    const __m128 a00 = _mm_cvtepi32_ps(_mm_and_si128(upper, low_byte)), a01 = _mm_cvtepi32_ps(_mm_srli_epi32(upper, 8));
    const __m128 a10 = _mm_cvtepi32_ps(_mm_and_si128(lower, low_byte)), a11 = _mm_cvtepi32_ps(_mm_srli_epi32(lower, 8));
    const __m128 top = _mm_add_ps(a00, _mm_mul_ps(_mm_sub_ps(a01, a00), fx));
    const __m128 bottom = _mm_add_ps(a10, _mm_mul_ps(_mm_sub_ps(a11, a10), fx));
    _mm_storeu_ps(out + k, _mm_add_ps(top, _mm_mul_ps(_mm_sub_ps(bottom, top), fy)));
  }
#else
  for (int k = 0; k < n; ++k) {
    const float u = cu + a * direction_x[k] + b * direction_y[k];
    const float v = cv + c * direction_x[k] + d * direction_y[k];
    const int x = static_cast<int>(u), y = static_cast<int>(v);
    out[k] = pixel_quad(x, y, u - x, v - y);
  }
#endif
  (void)pixel_quad;
}

}  // namespace rilbed::vision
