#pragma once
// Bit-level fingerprints of a run's state, for the determinism and the pinned-hash tests.

#include <drape/cloth/state.hpp>
#include <drape/rigid/world.hpp>

#include <Eigen/Core>
#include <catch2/catch.hpp>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <string>

namespace drape::test {

/// Whether this build may fuse a * b + c (-march=native on a processor with FMA, or -ffp-contract=fast with
/// FMA available). Then every result rounds differently from the pinned runs, and two differently inlined
/// copies of one expression may round differently from each other.
constexpr bool kMayFuse =
#if defined(__FMA__) || defined(__FP_FAST_FMA) || defined(__FP_FAST_FMAF)
    true;
#else
    false;
#endif

/// 64-bit FNV-1a over raw bytes.
class Fnv1a {
 public:
  void add(const void* data, std::size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < bytes; ++i) {
      hash_ ^= p[i];
      hash_ *= 1099511628211ull;
    }
  }
  template <class Derived> void addVector(const Eigen::MatrixBase<Derived>& v) {
    for (Eigen::Index k = 0; k < v.size(); ++k) {
      const auto c = v(k);
      add(&c, sizeof c);
    }
  }
  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = 14695981039346656037ull;
};

/// Adds the bits of a cloth state's local origin, positions and velocities.
template <class S> void addState(Fnv1a& f, const ClothState<S>& s) {
  f.add(s.origin.data(), 3 * sizeof(double));
  for (const auto& x : s.x) f.add(x.data(), 3 * sizeof(S));
  for (const auto& v : s.v) f.add(v.data(), 3 * sizeof(S));
}

/// Hash of the bits of a state's local origin, positions and velocities.
template <class S> std::uint64_t hashState(const ClothState<S>& s) {
  Fnv1a f;
  addState(f, s);
  return f.value();
}

/// Adds the bits of every body's pose and velocities.
inline void addBodies(Fnv1a& f, const RigidWorld& world) {
  for (int b = 0; b < world.bodyCount(); ++b) {
    const RigidBody& body = world.body(b);
    f.addVector(body.pose().position);
    f.addVector(body.pose().rotation.coeffs());
    f.addVector(body.linearVelocity());
    f.addVector(body.angularVelocity());
  }
}

inline std::string hex(std::uint64_t h) {
  char text[24];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(h));
  return text;
}

/// A run that ended anywhere but at finite positions and velocities has nothing worth pinning.
template <class Solver> void requireFinite(const Solver& solver) {
  for (Index i = 0; i < solver.vertexCount(); ++i) {
    REQUIRE(solver.position(i).allFinite());
    REQUIRE(solver.velocity(i).allFinite());
  }
}

/// The hash of a coupled scene: the cloth's state and every body's pose and velocities.
template <class Cloth> std::uint64_t hashClothAndBodies(const Cloth& cloth, const RigidWorld& world) {
  requireFinite(cloth);
  Fnv1a f;
  addState(f, cloth.state());
  addBodies(f, world);
  return f.value();
}

using PinnedHashes = std::map<std::string, std::uint64_t>;

/// Checks that run `name` ended in the hash `pinned` holds for it, unless `skip` says why this build cannot
/// (then only warns). With DRAPE_PRINT_HASHES set, prints the run's line of the table instead.
inline void checkPinned(const PinnedHashes& pinned, const std::string& name, std::uint64_t hash,
                        const std::string& skip = {}) {
  if (const char* print = std::getenv("DRAPE_PRINT_HASHES"); print && *print && *print != '0') {
    std::cout << "{\"" << name << "\", " << hex(hash) << "ull},\n";
    return;
  }
  if (!skip.empty()) {
    WARN(skip << ": " << name << " is not compared with its pinned hash");
    return;
  }
  const auto it = pinned.find(name);
  INFO("run " << name << " ended in state hash " << hex(hash));
  REQUIRE(it != pinned.end());
  CHECK(hex(hash) == hex(it->second));
}

}  // namespace drape::test
