// Test main: traps floating-point exceptions so a NaN or an overflow fails loudly where it happens.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include <cfenv>

int main(int argc, char* argv[]) {
#if defined(__GLIBC__)
  feenableexcept(FE_INVALID | FE_DIVBYZERO | FE_OVERFLOW);
#endif
  return Catch::Session().run(argc, argv);
}
