#pragma once
// Bit-level fingerprints of a run's state, for the determinism and the pinned-hash tests.

#include <drape/cloth/state.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

namespace drape::test {

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

inline std::string hex(std::uint64_t h) {
  char text[24];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(h));
  return text;
}

}  // namespace drape::test
