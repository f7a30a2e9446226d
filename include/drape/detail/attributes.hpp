#pragma once
// Inlining attributes, for hot paths and for large functions shared by many instantiations.

// A small function on a per-vertex path that the compiler would otherwise call (it weighs the rarely taken
// parts of the caller too).
#if defined(__GNUC__) || defined(__clang__)
#define DRAPE_ALWAYS_INLINE inline __attribute__((always_inline))
#elif defined(_MSC_VER)
#define DRAPE_ALWAYS_INLINE __forceinline
#else
#define DRAPE_ALWAYS_INLINE inline
#endif
// A large function called from many instantiations of its caller (each a combination of a scene's features):
// compiled once per its own template arguments rather than inlined into each, which costs build time.
#if defined(__GNUC__) || defined(__clang__)
#define DRAPE_NOINLINE __attribute__((noinline))
#elif defined(_MSC_VER)
#define DRAPE_NOINLINE __declspec(noinline)
#else
#define DRAPE_NOINLINE
#endif
