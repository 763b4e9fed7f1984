// Which sanitizer the tests are built with: gcc defines __SANITIZE_ADDRESS__ /
// __SANITIZE_THREAD__, clang answers __has_feature. Tests that cannot run under one say so.
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#define VMTEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define VMTEST_ASAN 1
#endif
#endif

#if defined(__SANITIZE_THREAD__)
#define VMTEST_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define VMTEST_TSAN 1
#endif
#endif

namespace vmtest {

#if defined(VMTEST_ASAN)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif
#if defined(VMTEST_TSAN)
inline constexpr bool kThreadSanitizer = true;
#else
inline constexpr bool kThreadSanitizer = false;
#endif

}  // namespace vmtest
