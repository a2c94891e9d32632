// Whether the tests run under AddressSanitizer (`./run asan`, a Debug build), where the
// detector runs some thirty times slower: the scene-rendering suites then render fewer
// scenes and hold them to the mistakes only.
#pragma once

namespace rilbed::vision {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
#else
inline constexpr bool kSanitized = false;
#endif

}  // namespace rilbed::vision
