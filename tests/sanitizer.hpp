#pragma once
// Whether this test binary is built with AddressSanitizer (the CI's second pass, at -O1, where a simulation
// runs about 20 times slower). The longest physics sweeps run a subset of their configurations there: the
// sanitizers look for memory errors and undefined behaviour, which the subset reaches on the same code paths,
// while the physical assertions over the whole sweep are the Release pass's.

namespace drape::test {

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

}  // namespace drape::test
