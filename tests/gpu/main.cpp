// The [gpu] tests' main. They need a GL 4.3+ context: without one, the binary says why on stderr and
// exits with 77, which ctest reports as "Skipped" (SKIP_RETURN_CODE) rather than as a pass. Listing the tests
// (ctest's discovery) needs no context. Unlike tests/main.cpp, floating-point exceptions are not trapped here:
// Mesa's shader compiler and llvmpipe's generated code may raise them in lanes whose results are discarded.
#define CATCH_CONFIG_RUNNER
#include "gpu_helpers.hpp"

#include <catch2/catch.hpp>

#include <cstdio>

int main(int argc, char* argv[]) {
  Catch::Session runner;
  if (const int rc = runner.applyCommandLine(argc, argv); rc != 0) return rc;
  const Catch::ConfigData& c = runner.configData();
  const bool listing = c.listTests || c.listTestNamesOnly || c.listTags || c.listReporters;
  if (!listing) {
    try {
      const drape::gpu::Context& context = drape::test::gpuContext();
      std::fprintf(stderr, "[gpu] %s context: %s, %s\n", drape::gpu::toString(context.backend()),
                   context.renderer().c_str(), context.version().c_str());
    } catch (const drape::Error& e) {
      std::fprintf(stderr,
                   "\n*** SKIPPED: the [gpu] tests need an OpenGL 4.3+ context and none could be made.\n*** %s\n\n",
                   e.what());
      return 77;
    }
  }
  return runner.run();
}
