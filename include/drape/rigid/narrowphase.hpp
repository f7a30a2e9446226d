#pragma once
// Narrow phase: contact between two convex shapes through libccd's MPR (Minkowski portal refinement), which
// gives the contact normal and the penetration depth; then a contact manifold of up to four points from the
// two shapes' supporting features (the face, edge or point each one turns to the other), clipped against each
// other as in Jolt's and Bullet's face clipping. One libccd point per pair would let a box resting on the
// ground rock from corner to corner; the manifold holds it on four.
//
// Needs libccd (link drape::rigid). Works with libccd built in double (Debian's) or float (ccd_real_t), which
// only changes how exact the normal is. libccd may divide by zero inside on degenerate portals; the call runs
// with floating-point traps held (feholdexcept), and its result is checked before use.

#include <drape/rigid/shapes.hpp>

#include <ccd/ccd.h>

#include <cfenv>
#include <cmath>
#include <type_traits>

namespace drape {

/// One contact point: the deepest point of each shape into the other, world (m). depth = (pointA - pointB) .
/// normal (m), positive when the shapes overlap there; a point within the contact margin but apart has a
/// small negative depth.
struct ContactPoint {
  Eigen::Vector3d pointA;
  Eigen::Vector3d pointB;
  double depth = 0;
};

/// The contact of shape A with shape B. `normal` (unit, world) points from A to B: B moves along it to separate.
struct Manifold {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  int count = 0;
  std::array<ContactPoint, 4> points;
  double ccdDepth = 0;  ///< libccd's penetration depth along the normal (m)
};

namespace detail {

struct CcdShape {
  const RigidShape* shape;
  Eigen::Matrix3d R;
  Eigen::Vector3d x;
};

inline Eigen::Vector3d fromCcd(const ccd_vec3_t& v) { return {double(v.v[0]), double(v.v[1]), double(v.v[2])}; }
inline void toCcd(const Eigen::Vector3d& p, ccd_vec3_t* v) {
  v->v[0] = ccd_real_t(p.x()), v->v[1] = ccd_real_t(p.y()), v->v[2] = ccd_real_t(p.z());
}

// libccd calls these through C function pointers (GCC and Clang give C++ functions the same type).
inline void ccdSupport(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const auto& s = *static_cast<const CcdShape*>(obj);
  toCcd(s.R * supportLocal(*s.shape, s.R.transpose() * fromCcd(*dir)) + s.x, out);
}
inline void ccdCentre(const void* obj, ccd_vec3_t* out) { toCcd(static_cast<const CcdShape*>(obj)->x, out); }

/// libccd's MPR penetration of B into A: normal from A to B, depth, and libccd's contact position.
inline bool mprPenetration(const CcdShape& a, const CcdShape& b, Eigen::Vector3d& normal, double& depth,
                           Eigen::Vector3d& position) {
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = ccdSupport;
  ccd.support2 = ccdSupport;
  ccd.center1 = ccdCentre;
  ccd.center2 = ccdCentre;
  ccd.max_iterations = 100;
  ccd.mpr_tolerance = std::is_same_v<ccd_real_t, double> ? ccd_real_t(1e-10) : ccd_real_t(1e-6);
  ccd_real_t d = 0;
  ccd_vec3_t dir, pos;
  std::fenv_t env;
  std::feholdexcept(&env);
  const int result = ccdMPRPenetration(&a, &b, &ccd, &d, &dir, &pos);
  std::fesetenv(&env);  // drops whatever libccd raised; its answer is checked below
  if (result != 0) return false;
  normal = fromCcd(dir);
  depth = double(d);
  position = fromCcd(pos);
  const double len = normal.norm();
  if (!std::isfinite(len) || len < 0.5 || !std::isfinite(depth) || !allFinite(position)) {
    // Degenerate portal (the centres coincide): fall back to the centre line, or +z.
    const Eigen::Vector3d c = b.x - a.x;
    normal = c.norm() > 0 ? Eigen::Vector3d(c.normalized()) : Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d sa = a.R * supportLocal(*a.shape, a.R.transpose() * normal) + a.x;
    const Eigen::Vector3d sb = b.R * supportLocal(*b.shape, -(b.R.transpose() * normal)) + b.x;
    depth = (sa - sb).dot(normal);
    position = 0.5 * (sa + sb);
    return depth >= 0;
  }
  normal /= len;
  return true;
}

/// Keeps the part of a feature (points q, count k) on the inner side of the plane s . (x - p) <= 0.
inline void clipByPlane(std::array<Eigen::Vector3d, 2 * kMaxFeaturePoints>& q, int& k, const Eigen::Vector3d& s,
                        const Eigen::Vector3d& p) {
  if (k == 0) return;
  std::array<Eigen::Vector3d, 2 * kMaxFeaturePoints> out;
  int m = 0;
  if (k == 1) {
    if (s.dot(q[0] - p) <= 0) out[m++] = q[0];
  } else if (k == 2) {  // a segment: clip its parameter interval
    const double d0 = s.dot(q[0] - p), d1 = s.dot(q[1] - p);
    if (d0 <= 0 && d1 <= 0) return;
    if (d0 > 0 && d1 > 0) {
      k = 0;
      return;
    }
    const Eigen::Vector3d cut = q[0] + (d0 / (d0 - d1)) * (q[1] - q[0]);
    (d0 > 0 ? q[0] : q[1]) = cut;
    return;
  } else {  // Sutherland-Hodgman
    for (int i = 0; i < k; ++i) {
      const Eigen::Vector3d& u = q[i];
      const Eigen::Vector3d& v = q[(i + 1) % k];
      const double du = s.dot(u - p), dv = s.dot(v - p);
      if (du <= 0) out[m++] = u;
      if ((du < 0 && dv > 0) || (du > 0 && dv < 0)) out[m++] = u + (du / (du - dv)) * (v - u);
      if (m >= 2 * kMaxFeaturePoints - 1) break;
    }
  }
  for (int i = 0; i < m; ++i) q[i] = out[i];
  k = m;
}

/// Clips `inc` against the side planes (containing n) of the polygon `ref` and returns the clipped points.
inline int clipAgainstPolygon(const Feature& ref, const Feature& inc, const Eigen::Vector3d& n,
                              std::array<Eigen::Vector3d, 2 * kMaxFeaturePoints>& q) {
  int k = inc.count;
  for (int i = 0; i < k; ++i) q[i] = inc.points[i];
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int i = 0; i < ref.count; ++i) centre += ref.points[i];
  centre /= ref.count;
  for (int i = 0; i < ref.count && k > 0; ++i) {
    const Eigen::Vector3d& p0 = ref.points[i];
    const Eigen::Vector3d& p1 = ref.points[(i + 1) % ref.count];
    Eigen::Vector3d s = (p1 - p0).cross(n);
    if (s.dot(centre - p0) > 0) s = -s;
    clipByPlane(q, k, s, p0);
  }
  return k;
}

/// Four of `count` points spanning the largest area: the deepest, the farthest from it, the one making the
/// largest triangle, and the one adding the most area outside that triangle.
inline void reduceToFour(std::array<ContactPoint, 2 * kMaxFeaturePoints>& c, int& count, const Eigen::Vector3d& n) {
  if (count <= 4) return;
  std::array<int, 4> pick{};
  auto argmax = [&](auto score) {
    int best = 0;
    double bestS = -INFINITY;
    for (int i = 0; i < count; ++i) {
      const double s = score(c[i].pointB);
      if (s > bestS) best = i, bestS = s;
    }
    return best;
  };
  pick[0] = 0;
  for (int i = 1; i < count; ++i)
    if (c[i].depth > c[pick[0]].depth) pick[0] = i;
  const Eigen::Vector3d p0 = c[pick[0]].pointB;
  pick[1] = argmax([&](const Eigen::Vector3d& p) { return (p - p0).squaredNorm(); });
  const Eigen::Vector3d p1 = c[pick[1]].pointB;
  pick[2] = argmax([&](const Eigen::Vector3d& p) { return std::abs((p1 - p0).cross(p - p0).dot(n)); });
  const Eigen::Vector3d p2 = c[pick[2]].pointB;
  const double area = std::abs((p1 - p0).cross(p2 - p0).dot(n));
  pick[3] = argmax([&](const Eigen::Vector3d& p) {
    return std::abs((p1 - p0).cross(p - p0).dot(n)) + std::abs((p2 - p1).cross(p - p1).dot(n)) +
           std::abs((p0 - p2).cross(p - p2).dot(n)) - area;
  });
  std::array<ContactPoint, 4> chosen;
  for (int i = 0; i < 4; ++i) chosen[i] = c[pick[i]];
  for (int i = 0; i < 4; ++i) c[i] = chosen[i];
  count = 4;
}

}  // namespace detail

/// Contact between shape A placed by (Ra, xa) and shape B placed by (Rb, xb). Returns false when they do not
/// overlap. Manifold points apart by more than `margin` (m) are dropped.
inline bool collide(const RigidShape& a, const Eigen::Matrix3d& Ra, const Eigen::Vector3d& xa, const RigidShape& b,
                    const Eigen::Matrix3d& Rb, const Eigen::Vector3d& xb, double margin, Manifold& out) {
  using namespace detail;
  const CcdShape ca{&a, Ra, xa}, cb{&b, Rb, xb};
  Eigen::Vector3d n, position;
  double ccdDepth = 0;
  if (!mprPenetration(ca, cb, n, ccdDepth, position)) return false;
  out.normal = n;
  out.ccdDepth = ccdDepth;
  out.count = 0;

  const Feature fa = supportingFeature(a, Ra, xa, n);
  const Feature fb = supportingFeature(b, Rb, xb, -n);
  std::array<Eigen::Vector3d, 2 * kMaxFeaturePoints> q;
  std::array<ContactPoint, 2 * kMaxFeaturePoints> c;
  int count = 0;
  constexpr double kMinAlign = 1e-3;  // a reference face must not be edge-on to the normal
  const double alignA = fa.count >= 3 ? fa.normal.dot(n) : 0, alignB = fb.count >= 3 ? -fb.normal.dot(n) : 0;
  if (fa.count >= 3 && alignA > kMinAlign && alignA >= alignB) {
    const int k = clipAgainstPolygon(fa, fb, n, q);
    for (int i = 0; i < k; ++i) {  // q on B; A's point is on A's face plane along n
      const double t = (fa.points[0] - q[i]).dot(fa.normal) / alignA;
      c[count++] = {q[i] + t * n, q[i], t};
    }
  } else if (fb.count >= 3 && alignB > kMinAlign) {
    const int k = clipAgainstPolygon(fb, fa, n, q);
    for (int i = 0; i < k; ++i) {  // q on A; B's point is on B's face plane along n
      const double u = (fb.points[0] - q[i]).dot(fb.normal) / -alignB;
      c[count++] = {q[i], q[i] + u * n, -u};
    }
  } else if (fa.count == 2 && fb.count == 2) {
    Eigen::Vector3d da = fa.points[1] - fa.points[0], db = fb.points[1] - fb.points[0];
    da -= da.dot(n) * n, db -= db.dot(n) * n;
    const double la = da.norm(), lb = db.norm();
    if (la > 0 && lb > 0 && da.cross(db).norm() < 0.05 * la * lb) {  // parallel within ~3 degrees
      da /= la;
      int k = 2;
      q[0] = fb.points[0], q[1] = fb.points[1];
      clipByPlane(q, k, -da, fa.points[0]);
      clipByPlane(q, k, da, fa.points[1]);
      Eigen::Vector3d m = (fa.points[1] - fa.points[0]).normalized();
      m = (n - n.dot(m) * m).normalized();  // normal of the plane holding A's segment, facing B
      for (int i = 0; i < k; ++i) {
        const double t = (fa.points[0] - q[i]).dot(m) / n.dot(m);
        c[count++] = {q[i] + t * n, q[i], t};
      }
    }
  }
  int kept = 0;
  for (int i = 0; i < count; ++i)
    if (c[i].depth >= -margin) c[kept++] = c[i];
  count = kept;
  if (count == 0) {  // one point: the deepest along n, placed on whichever side is a single point
    const Eigen::Vector3d sa = Ra * supportLocal(a, Ra.transpose() * n) + xa;
    const Eigen::Vector3d sb = Rb * supportLocal(b, -(Rb.transpose() * n)) + xb;
    const double depth = (sa - sb).dot(n);
    if (fa.count == 1)
      c[0] = {sa, sa - depth * n, depth};
    else if (fb.count == 1)
      c[0] = {sb + depth * n, sb, depth};
    else
      c[0] = {position + 0.5 * depth * n, position - 0.5 * depth * n, depth};
    count = 1;
  }
  // No point deeper than MPR's own depth along n. Where the portal stopped on a degenerate face (shapes just
  // touching, or apart while MPR still says they meet) MPR's depth is about 0 but its normal can be far from the
  // true one, and the supporting features along that normal overlap by centimetres: a 4.4 cm "depth" between
  // two cylinders that did not touch once spun a rain body to 566 rad/s in one substep. The excess is taken off
  // both points alike, so the contact's centre stays where the features put it.
  for (int i = 0; i < count; ++i) {
    const double excess = c[i].depth - std::max(ccdDepth, 0.0);
    if (!(excess > 0)) continue;
    c[i].pointA -= 0.5 * excess * n;
    c[i].pointB += 0.5 * excess * n;
    c[i].depth -= excess;
  }
  reduceToFour(c, count, n);
  for (int i = 0; i < count; ++i) out.points[i] = c[i];
  out.count = count;
  return true;
}

/// Contact of a shape (B, placed by R, x) with the ground z <= height: through libccd as well, the ground
/// being a box under the shape, wider and deeper than the shape, so that its top face is all it can reach.
inline bool collideGround(const RigidShape& shape, const Eigen::Matrix3d& R, const Eigen::Vector3d& x, double height,
                          double margin, Manifold& out) {
  const double half = detail::boundingRadius(shape) + 1;
  const RigidShape slab = Box{Eigen::Vector3d::Constant(half)};
  return collide(slab, Eigen::Matrix3d::Identity(), Eigen::Vector3d(x.x(), x.y(), height - half), shape, R, x, margin,
                 out);
}

}  // namespace drape
