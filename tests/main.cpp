// Test main: traps floating-point exceptions so a NaN or an overflow fails loudly where it happens.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include <cfenv>

#if defined(__GLIBC__)
#include <csignal>
#include <cstdio>
#include <limits>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#endif

namespace {
#if defined(__GLIBC__)
constexpr int kTrappedExceptions = FE_INVALID | FE_DIVBYZERO | FE_OVERFLOW;
#endif
}  // namespace

int main(int argc, char* argv[]) {
#if defined(__GLIBC__)
  feenableexcept(kTrappedExceptions);
#endif
  return Catch::Session().run(argc, argv);
}

// --- The traps are really on -------------------------------------------------------------------------------
#if defined(__GLIBC__)
namespace {

/// Runs f() in a forked child with SIGFPE's default action (no Catch or sanitizer handler, no core file) and
/// returns the signal that ended the child, or 0 if f() returned and the child exited normally.
template <class F> int signalEndingChild(F f) {
  std::fflush(nullptr);  // nothing buffered is written twice
  const pid_t pid = fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    struct sigaction action {};
    action.sa_handler = SIG_DFL;
    sigemptyset(&action.sa_mask);
    sigaction(SIGFPE, &action, nullptr);
    const rlimit noCore{0, 0};
    setrlimit(RLIMIT_CORE, &noCore);
    f();
    _exit(0);
  }
  int status = 0;
  REQUIRE(waitpid(pid, &status, 0) == pid);
  INFO("child status " << status);
  if (WIFSIGNALED(status)) return WTERMSIG(status);
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);
  return 0;
}

// volatile operands and results: the compiler can neither fold the operation away nor drop it.
template <class T> void divideByZero() {
  volatile T one = 1, zero = 0;
  volatile T r = one / zero;
  (void)r;
}
template <class T> void zeroOverZero() {
  volatile T zero = 0;
  volatile T r = zero / zero;
  (void)r;
}
template <class T> void overflow() {
  volatile T big = std::numeric_limits<T>::max();
  volatile T r = big * big;
  (void)r;
}
template <class T> void harmless() {
  volatile T one = 1, three = 3;
  volatile T r = one / three;  // inexact only, which is not trapped
  (void)r;
}

}  // namespace

TEST_CASE("the test main enables traps for invalid, divide-by-zero and overflow", "[fpe]") {
  CHECK((fegetexcept() & kTrappedExceptions) == kTrappedExceptions);
}

TEMPLATE_TEST_CASE("a trapped floating-point exception kills the process with SIGFPE", "[fpe]", float, double) {
  CHECK(signalEndingChild(divideByZero<TestType>) == SIGFPE);
  CHECK(signalEndingChild(zeroOverZero<TestType>) == SIGFPE);
  CHECK(signalEndingChild(overflow<TestType>) == SIGFPE);
  CHECK(signalEndingChild(harmless<TestType>) == 0);  // the harness itself does not report SIGFPE
}
#endif
