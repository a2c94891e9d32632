// Cache state of a frame for the benchmarks: flushed from every cache level, as a frame
// arrives from a camera (written to memory by the capture hardware), or read once so
// that it sits in the caches.
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace rilbed::bench {

/// Flushes every cache line of `frame`'s pixels from all cache levels (clflush) and
/// waits for that to finish. Without SSE2 it does nothing (no portable eviction).
inline void evict(const cv::Mat& frame) {
#if defined(__SSE2__)
  const std::size_t bytes = frame.cols * frame.elemSize();
  for (int y = 0; y < frame.rows; ++y) {
    const std::uint8_t* row = frame.ptr<std::uint8_t>(y);
    for (std::size_t x = 0; x < bytes; x += 64) _mm_clflush(row + x);
    _mm_clflush(row + bytes - 1);
  }
  _mm_mfence();
#else
  (void)frame;
#endif
}

/// Reads one byte of every cache line of `frame`'s pixels, so that they are cached.
inline void touch(const cv::Mat& frame) {
  const std::size_t bytes = frame.cols * frame.elemSize();
  unsigned sum = 0;
  for (int y = 0; y < frame.rows; ++y) {
    const std::uint8_t* row = frame.ptr<std::uint8_t>(y);
    for (std::size_t x = 0; x < bytes; x += 64) sum += row[x];
  }
  volatile unsigned sink = sum;
  (void)sink;
}

}  // namespace rilbed::bench
