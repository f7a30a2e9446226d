#pragma once
// Eigen aliases, the library's error type, rigid poses and input checks.

#include <drape/detail/attributes.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace drape {

/// Vertex, face and constraint indices.
using Index = std::int32_t;

template <class S> using Vec2 = Eigen::Matrix<S, 2, 1>;
template <class S> using Vec3 = Eigen::Matrix<S, 3, 1>;
template <class S> using Vec4 = Eigen::Matrix<S, 4, 1>;
template <class S> using Mat3 = Eigen::Matrix<S, 3, 3>;

/// Scalars the solver is instantiated for.
template <class S>
concept Scalar = std::is_same_v<S, float> || std::is_same_v<S, double>;

/// a + s n, written out: on a hot path GCC compiled the Eigen expression into a call, whose three stores the
/// caller then read back as one wide load, a store-forwarding stall each time.
template <Scalar S> DRAPE_ALWAYS_INLINE Vec3<S> movedAlong(const Vec3<S>& a, S s, const Vec3<S>& n) {
  return Vec3<S>(a.x() + s * n.x(), a.y() + s * n.y(), a.z() + s * n.z());
}

namespace detail {
/// a . b as a0 b0 + (a1 b1 + a2 b2), and a - b, written out: in the face pass, too large for GCC's inliner,
/// Eigen's reductions became calls. The order is Eigen's for float; for double, summed in SSE pairs, Eigen's is
/// (a0 b0 + a1 b1) + a2 b2, so a field whose bits must not move keeps Eigen's sums (Sdf<Capsule>::fromCore).
template <Scalar S> DRAPE_ALWAYS_INLINE S dot3(const Vec3<S>& a, const Vec3<S>& b) {
  return a.x() * b.x() + (a.y() * b.y() + a.z() * b.z());
}
template <Scalar S> DRAPE_ALWAYS_INLINE Vec3<S> minus3(const Vec3<S>& a, const Vec3<S>& b) {
  return Vec3<S>(a.x() - b.x(), a.y() - b.y(), a.z() - b.z());
}
}  // namespace detail

/// The square root through Eigen's scalar root, an SSE instruction on x86: for std::sqrt, which may set errno,
/// GCC keeps a call to libm beside the instruction, and on the face pass's paths called it every time. The same
/// correctly rounded result.
template <Scalar S> inline S rootOf(S x) { return Eigen::numext::sqrt(x); }

/// The largest absolute coordinate, written out: on a hot path Eigen's reduction became a call.
template <Scalar S> inline S largestAbs(const Vec3<S>& a) {
  return std::max(std::max(std::abs(a.x()), std::abs(a.y())), std::abs(a.z()));
}

/// Every rejected input throws this, with a message that names what was wrong. It is thrown before any
/// state changes.
struct Error : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

/// The limits a solver checks what it is given against.
namespace limits {
inline constexpr double kRebaseDistance = 0.5;  ///< m the cloth's centre may drift from its local origin
inline constexpr double kMaxDistance = 1e5;     ///< m, largest accepted offset from the local origin
inline constexpr double kMaxCoordinate = 1e9;   ///< m, largest accepted world coordinate
inline constexpr double kMaxSpeed = 1e5;        ///< m/s, largest accepted velocity component
inline constexpr double kMaxStep = 10;          ///< s, longest accepted step
inline constexpr double kMinSubStep = 1e-6;     ///< s, below this h^2 underflows float
inline constexpr double kOriginLattice = 64;    ///< local origins sit on a 1/64 m lattice (exact shifts in float)
/// m/s^2, largest accepted gravity component: a 10 s step from rest then ends 5e7 m away at 1e7 m/s, where
/// squared lengths still fit in float.
inline constexpr double kMaxAcceleration = 1e6;
/// m, largest accepted size of an analytic shape (a radius, a half extent or a half height): the cloth a solid
/// pushes out stays within kMaxDistance of it.
inline constexpr double kMaxShapeSize = 1e5;
}  // namespace limits

/// A rigid placement in world coordinates (metres), always in double so that large worlds stay exact.
struct Pose {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d position = Eigen::Vector3d::Zero();

  Eigen::Vector3d apply(const Eigen::Vector3d& local) const { return rotation * local + position; }
};

namespace detail {

/// Eigen's allFinite() computes x - x, which raises FE_INVALID on infinity; this asks each coefficient.
template <class Derived> bool allFinite(const Eigen::MatrixBase<Derived>& m) { return m.array().isFinite().all(); }

/// A number as a message shows it: six significant digits, so 1e-10 reads as 1e-10 rather than 0.000000.
inline std::string formatNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

inline void require(bool ok, const std::string& what) {
  if (!ok) throw Error("drape: " + what);
}
/// A fixed message: no string is made unless it is thrown.
inline void require(bool ok, const char* what) {
  if (!ok) throw Error(std::string("drape: ") + what);
}

/// The same with a message made only on failure, for checks on a path taken every step or substep (formatting
/// numbers into a message that is thrown away cost the rigid-body rain a sixth of its time).
template <class Message>
  requires std::is_invocable_r_v<std::string, Message>
inline void require(bool ok, Message&& what) {
  if (!ok) throw Error("drape: " + what());
}

inline void requireFinite(double value, const std::string& name) {
  require(std::isfinite(value), name + " must be finite (got " + formatNumber(value) + ")");
}

inline void requireRange(double value, double lo, double hi, const std::string& name) {
  require(std::isfinite(value) && value >= lo && value <= hi,
          name + " must be in [" + formatNumber(lo) + ", " + formatNumber(hi) + "] (got " + formatNumber(value) +
              ")");
}

}  // namespace detail
}  // namespace drape
