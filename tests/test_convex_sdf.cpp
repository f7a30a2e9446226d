// Cylinder and convex hull distance fields (drape/sdf/convex.hpp). The references share no code with the
// fields: the cylinder's is the closest point on each of its three surface pieces (side, two caps) in Cartesian
// coordinates, checked in turn against a dense sampling of the surface; the hull's is the closest point on each
// triangle of a fan of each face polygon (Ericson's region test), signed by the face-plane test. Each field is
// evaluated at a float- or double-rounded point and the reference at that same point.
#include <drape/sdf/convex.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

// Each test source keeps its helpers in a namespace of its own: the tests build as unity batches.
namespace convex_sdf_tests {

namespace {

using namespace drape;
using Catch::Matchers::Contains;
using Vec = Eigen::Vector3d;

template <class S> constexpr bool kFloat = std::is_same_v<S, float>;
/// Largest |phi - reference| allowed for shapes and points within a few metres of the origin.
template <class S> constexpr double kPhiTol = kFloat<S> ? 2e-6 : 1e-13;
/// Largest |normal - reference| allowed where the closest point is at least kClear away and unique.
template <class S> constexpr double kNormalTol = kFloat<S> ? 1e-4 : 1e-10;
constexpr double kClear = 1e-2;

template <class S> Vec rounded(const Vec& x) { return x.cast<S>().template cast<double>(); }

/// phi and normal of a field at x (rounded to S), in double.
template <class Shape, Scalar S> double sampleAt(const Sdf<Shape, S>& f, const Vec& x, Vec* normal = nullptr) {
  Vec3<S> g;
  const double phi = double(f(x.cast<S>(), g));
  if (normal) *normal = g.template cast<double>();
  return phi;
}

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}
Vec randomUnit(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0, 1);
  for (;;) {
    const double x = n(rng), y = n(rng), z = n(rng);  // (named: the order of arguments is unspecified)
    const Vec v(x, y, z);
    if (v.norm() > 1e-6) return v.normalized();
  }
}
Vec randomInBox(std::mt19937_64& rng, const Vec& lo, const Vec& hi) {
  const double x = uniform(rng, lo.x(), hi.x()), y = uniform(rng, lo.y(), hi.y()), z = uniform(rng, lo.z(), hi.z());
  return Vec(x, y, z);
}

/// A generic pose and a cloth origin away from it (both tests of posing use it).
Pose genericPose() {
  Pose pose;
  pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.83, Vec(1, -2, 0.7).normalized()));
  pose.position = Vec(1.7, -0.9, 2.3);
  return pose;
}
const Vec kOrigin(1.2, -1.4, 1.9);

// --- Cylinder reference ----------------------------------------------------------------------------------------

struct Reference {
  double phi;       ///< signed distance
  Vec closest;      ///< a closest surface point
  double gap;       ///< distance of the next-nearest surface piece (face) minus phi's magnitude; inf if none
  Vec pieceNormal;  ///< outward normal of the nearest piece (face), where it has one
};

/// The closest point on each of the side (the circle at p's angle, z clamped), the top and the bottom cap (p's
/// (x, y) pulled onto the disc); the nearest wins. Inside when within the radius and the height.
Reference cylinderReference(const Cylinder& c, const Vec& p) {
  const double r = std::sqrt(p.x() * p.x() + p.y() * p.y());
  const Vec radial = r > 0 ? Vec(p.x() / r, p.y() / r, 0) : Vec(1, 0, 0);
  Eigen::Vector2d disc = p.head<2>();
  if (r > c.radius) disc *= c.radius / r;
  const std::pair<Vec, Vec> pieces[3] = {
      {c.radius * radial + Vec(0, 0, std::clamp(p.z(), -c.halfHeight, c.halfHeight)), radial},
      {Vec(disc.x(), disc.y(), c.halfHeight), Vec(0, 0, 1)},
      {Vec(disc.x(), disc.y(), -c.halfHeight), Vec(0, 0, -1)}};
  double d[3];
  for (int i = 0; i < 3; ++i) d[i] = (p - pieces[i].first).norm();
  const int best = int(std::min_element(d, d + 3) - d);
  double next = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i)
    if (i != best) next = std::min(next, d[i]);
  const bool inside = r <= c.radius && std::abs(p.z()) <= c.halfHeight;
  return {inside ? -d[best] : d[best], pieces[best].first, next - d[best], pieces[best].second};
}

const std::vector<Cylinder>& cylinders() {
  static const std::vector<Cylinder> c = {{0.3, 0.5}, {0.6, 0.08}, {0.25, 0.25}};
  return c;
}

/// Random points around a cylinder: in a box twice its size, and near its side, caps, rims and axis.
std::vector<Vec> cylinderPoints(const Cylinder& c, int count, unsigned seed) {
  std::mt19937_64 rng(seed);
  const Vec half(c.radius, c.radius, c.halfHeight);
  std::vector<Vec> out;
  for (int i = 0; i < count; ++i) {
    const double a = uniform(rng, 0, 2 * std::numbers::pi);
    const Vec radial(std::cos(a), std::sin(a), 0);
    const double u = uniform(rng, -1, 1), w = uniform(rng, -1, 1);
    const Vec jitter = randomUnit(rng);
    const Vec cap(0, 0, (i % 12 < 6 ? 1 : -1) * c.halfHeight);
    switch (i % 6) {
      case 0:
      case 1: out.push_back(randomInBox(rng, -2 * half, 2 * half)); break;
      // Within a tenth of the radius or half height of the side, a cap, a rim; near the axis.
      case 2: out.push_back(c.radius * radial + Vec(0, 0, u * c.halfHeight) + 0.1 * c.radius * w * jitter); break;
      case 3: out.push_back(std::abs(u) * c.radius * radial + cap + 0.1 * c.halfHeight * w * jitter); break;
      case 4: out.push_back(c.radius * radial + cap + 0.1 * c.radius * std::abs(w) * jitter); break;
      default: out.push_back(Vec(0, 0, 2 * u * c.halfHeight) + 1e-3 * c.radius * jitter); break;
    }
  }
  return out;
}

// --- Hull reference --------------------------------------------------------------------------------------------

/// The closest point of triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
Vec closestOnTriangle(const Vec& p, const Vec& a, const Vec& b, const Vec& c) {
  const Vec ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Vec cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

/// Nearest point over the fan triangles of every face; inside when behind every face plane.
Reference hullReference(const ConvexHull& h, const Vec& p) {
  const auto& v = h.vertices();
  bool inside = true;
  double best = std::numeric_limits<double>::infinity(), next = best;
  Vec closest = Vec::Zero(), normal = Vec::UnitZ();
  for (const auto& f : h.faces()) {
    const Vec& a = v[f.vertices[0]];
    if (f.normal.dot(p - a) > 0) inside = false;
    double faceBest = std::numeric_limits<double>::infinity();
    Vec faceClosest = a;
    for (std::size_t k = 1; k + 1 < f.vertices.size(); ++k) {
      const Vec& b = v[f.vertices[k]];
      const Vec& c = v[f.vertices[k + 1]];
      if ((b - a).cross(c - a).norm() < 1e-12) continue;  // collinear: its points are on other triangles
      const Vec q = closestOnTriangle(p, a, b, c);
      const double d = (p - q).norm();
      if (d < faceBest) faceBest = d, faceClosest = q;
    }
    if (faceBest < best) {
      next = best, best = faceBest, closest = faceClosest, normal = f.normal;
    } else {
      next = std::min(next, faceBest);
    }
  }
  return {inside ? -best : best, closest, next - best, normal};
}

struct HullCase {
  std::string name;
  ConvexHull hull;
};

const std::vector<HullCase>& hulls() {
  static const std::vector<HullCase> cases = [] {
    std::vector<HullCase> out;
    out.push_back(
        {"tetrahedron", ConvexHull({Vec(0, 0, 0), Vec(0.9, 0.1, 0), Vec(0.2, 0.7, 0.1), Vec(0.3, 0.2, 0.6)})});
    std::vector<Vec> box;
    for (int i = 0; i < 8; ++i) box.emplace_back(i & 1 ? 0.4 : -0.4, i & 2 ? 0.3 : -0.3, i & 4 ? 0.2 : -0.2);
    out.push_back({"box", ConvexHull(box)});
    std::vector<Vec> prism, slab;
    for (int k = 0; k < 6; ++k) {
      const double a = k * std::numbers::pi / 3;
      for (double z : {-0.3, 0.3}) prism.emplace_back(0.5 * std::cos(a), 0.5 * std::sin(a), z);
    }
    out.push_back({"hexagonal prism", ConvexHull(prism)});
    for (int k = 0; k < 8; ++k) {
      const double a = k * std::numbers::pi / 4 + 0.1;
      for (double z : {-0.04, 0.04}) slab.emplace_back(0.6 * std::cos(a), 0.5 * std::sin(a), z);
    }
    out.push_back({"thin octagonal slab", ConvexHull(slab)});
    std::mt19937_64 rng(5);
    std::vector<Vec> ellipsoid, cube;
    for (int i = 0; i < 60; ++i)
      ellipsoid.push_back(randomUnit(rng).cwiseProduct(Vec(0.6, 0.4, 0.3)) + Vec(0.2, 0.1, -0.1));
    out.push_back({"60 points on an ellipsoid", ConvexHull(ellipsoid)});
    for (int i = 0; i < 40; ++i) cube.push_back(randomInBox(rng, Vec(-0.5, -0.3, -0.4), Vec(0.5, 0.3, 0.4)));
    out.push_back({"40 points in a box", ConvexHull(cube)});
    return out;
  }();
  return cases;
}

/// Random points around a hull: in its bounding box grown by half its size, near the middle of faces (both
/// sides), near edges and near vertices.
std::vector<Vec> hullPoints(const ConvexHull& h, int count, unsigned seed) {
  std::mt19937_64 rng(seed);
  const auto& v = h.vertices();
  Vec lo = v[0], hi = v[0];
  for (const auto& p : v) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double size = (hi - lo).maxCoeff();
  std::exponential_distribution<double> expo(1);
  std::vector<Vec> out;
  for (int i = 0; i < count; ++i) {
    const auto& f = h.faces()[std::size_t(uniform(rng, 0, double(h.faces().size()) - 1e-9))];
    const int n = int(f.vertices.size());
    const int k = int(uniform(rng, 0, n - 1e-9));
    const Vec& a = v[f.vertices[k]];
    const Vec& b = v[f.vertices[(k + 1) % n]];
    switch (i % 4) {
      case 0: case 1: out.push_back(randomInBox(rng, lo - 0.5 * (hi - lo), hi + 0.5 * (hi - lo))); break;
      case 2: {  // a random point of the face, moved off it
        Vec p = Vec::Zero();
        double w = 0;
        for (int j : f.vertices) {
          const double e = expo(rng);
          p += e * v[j], w += e;
        }
        out.push_back(p / w + uniform(rng, -0.1, 0.1) * size * f.normal);
        break;
      }
      default: {  // near an edge or a vertex
        const double t = i % 8 == 3 ? uniform(rng, 0, 1) : 0.0, r = uniform(rng, 0, 0.05) * size;
        out.push_back(a + t * (b - a) + r * randomUnit(rng));
        break;
      }
    }
  }
  return out;
}

template <Scalar S> Sdf<ConvexHull, S> unposed(const ConvexHull& h) {
  return detail::compileSdf<S>(h, Pose{}, Vec::Zero());
}
template <Scalar S> Sdf<Cylinder, S> unposed(const Cylinder& c) {
  return detail::compileSdf<S>(c, Pose{}, Vec::Zero());
}

/// Central differences of phi along the axes with step h.
template <class Field> Vec finiteDifference(const Field& f, const Vec& x, double h) {
  Vec g;
  for (int a = 0; a < 3; ++a) {
    const Vec e = h * Vec::Unit(a);
    g[a] = (sampleAt(f, x + e) - sampleAt(f, x - e)) / (2 * h);
  }
  return g;
}

}  // namespace

// --- Declarations and validation -----------------------------------------------------------------------------

TEST_CASE("cylinder dimensions are checked, naming the field, a hull without faces is refused", "[convexsdf]") {
  STATIC_REQUIRE(!Sdf<Cylinder, float>::kLinear);
  STATIC_REQUIRE(Sdf<Cylinder, double>::kConvex);
  STATIC_REQUIRE(!Sdf<ConvexHull, double>::kLinear);
  STATIC_REQUIRE(Sdf<ConvexHull, float>::kConvex);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  CHECK_NOTHROW(detail::validateShape(Cylinder{0.2, 0.5}));
  for (double bad : {0.0, -0.1, nan, inf}) {
    INFO("bad value " << bad);
    CHECK_THROWS_AS(detail::validateShape(Cylinder{bad, 0.5}), Error);
    CHECK_THROWS_WITH(detail::validateShape(Cylinder{bad, 0.5}), Contains("cylinder radius"));
    CHECK_THROWS_WITH(detail::validateShape(Cylinder{0.2, bad}), Contains("cylinder halfHeight"));
  }
  ConvexHull h = hulls()[1].hull;
  CHECK_NOTHROW(detail::validateShape(h));
  CHECK_NOTHROW(detail::compileSdf<double>(h, Pose{}, Vec::Zero()));
  const ConvexHull taken = std::move(h);
  CHECK(taken.faces().size() == 6);
  CHECK_THROWS_WITH(detail::compileSdf<float>(h, Pose{}, Vec::Zero()), Contains("convex hull has no faces"));
}

// --- Exactness -----------------------------------------------------------------------------------------------

TEMPLATE_TEST_CASE("cylinder: the exact signed distance, and the direction from the closest point", "[convexsdf]",
                   float, double) {
  using S = TestType;
  const Cylinder c = cylinders()[GENERATE(0u, 1u, 2u)];  // (generated: a section in a loop runs once)
  INFO("radius " << c.radius << ", halfHeight " << c.halfHeight);
  const auto sdf = unposed<S>(c);

  SECTION("against the closest point on each surface piece") {
    double worstPhi = 0, worstNormal = 0;
    for (const Vec& x : cylinderPoints(c, 6000, 3)) {
      const Vec p = rounded<S>(x);
      INFO("point " << p.transpose());
      Vec g;
      const double phi = sampleAt(sdf, p, &g);
      const Reference ref = cylinderReference(c, p);
      worstPhi = std::max(worstPhi, std::abs(phi - ref.phi));
      CHECK(std::abs(phi - ref.phi) <= kPhiTol<S>);
      CHECK(std::abs(g.norm() - 1) <= 10 * std::numeric_limits<S>::epsilon());
      // A unique closest point kClear away: the normal points away from it (outside) or at it (inside).
      const double r = p.head<2>().norm();
      if (std::abs(ref.phi) > kClear && (ref.phi > 0 || (ref.gap > kClear && r > kClear))) {
        const Vec expected = (p - ref.closest) / ref.phi;
        worstNormal = std::max(worstNormal, (g - expected).norm());
        CHECK((g - expected).norm() <= kNormalTol<S>);
      }
    }
    INFO("worst |phi - reference| " << worstPhi << ", worst normal error " << worstNormal);
    CHECK(worstPhi <= kPhiTol<S>);
  }

  SECTION("against a dense sampling of the surface, within its spacing") {
    // Side: 512 angles x 129 heights; caps: 65 rings x 512 angles. No surface point is farther from a sample
    // than half the diagonal of a cell (a chord is shorter than its arc).
    const int angles = 512, heights = 129, rings = 65;
    const double da = 2 * std::numbers::pi / angles;
    std::vector<Vec> samples;
    for (int i = 0; i < angles; ++i) {
      const Vec radial(std::cos(i * da), std::sin(i * da), 0);
      for (int k = 0; k < heights; ++k)
        samples.push_back(c.radius * radial + Vec(0, 0, c.halfHeight * (2.0 * k / (heights - 1) - 1)));
      for (int k = 0; k < rings; ++k)
        for (double z : {-c.halfHeight, c.halfHeight})
          samples.push_back(c.radius * k / (rings - 1) * radial + Vec(0, 0, z));
    }
    const double spacing = 0.5 * std::max(std::hypot(c.radius * da, 2 * c.halfHeight / (heights - 1)),
                                          std::hypot(c.radius * da, c.radius / (rings - 1)));
    double worstBelow = 0, worstAbove = 0;
    for (const Vec& x : cylinderPoints(c, 300, 11)) {
      const Vec p = rounded<S>(x);
      double brute = std::numeric_limits<double>::infinity();
      for (const Vec& s : samples) brute = std::min(brute, (p - s).squaredNorm());
      brute = std::sqrt(brute);
      const double phi = std::abs(sampleAt(sdf, p));
      INFO("point " << p.transpose() << ": |phi| " << phi << ", nearest sample " << brute);
      worstBelow = std::max(worstBelow, phi - brute);
      worstAbove = std::max(worstAbove, brute - phi);
      CHECK(phi <= brute + kPhiTol<S>);              // the surface is at least as near as any sample
      CHECK(brute <= phi + spacing + kPhiTol<S>);    // and some sample is within the spacing of it
    }
    INFO("spacing " << spacing << ": |phi| above the nearest sample by " << worstBelow << ", below by at most "
                    << worstAbove);
    CHECK(worstAbove <= spacing + kPhiTol<S>);
  }
}

TEMPLATE_TEST_CASE("convex hull: the exact signed distance, and the direction from the closest point", "[convexsdf]",
                   float, double) {
  using S = TestType;
  double worstPhi = 0, worstNormal = 0;
  for (const auto& hc : hulls()) {
    INFO(hc.name << ": " << hc.hull.vertices().size() << " vertices, " << hc.hull.faces().size() << " faces");
    const auto sdf = unposed<S>(hc.hull);
    for (const Vec& x : hullPoints(hc.hull, 4000, 7)) {
      const Vec p = rounded<S>(x);
      INFO("point " << p.transpose());
      Vec g;
      const double phi = sampleAt(sdf, p, &g);
      const Reference ref = hullReference(hc.hull, p);
      worstPhi = std::max(worstPhi, std::abs(phi - ref.phi));
      CHECK(std::abs(phi - ref.phi) <= kPhiTol<S>);
      CHECK(std::abs(g.norm() - 1) <= 10 * std::numeric_limits<S>::epsilon());
      // Outside the closest point is unique; inside it is where the nearest face is nearer than the next.
      if (std::abs(ref.phi) > kClear && (ref.phi > 0 || ref.gap > kClear)) {
        const Vec expected = (p - ref.closest) / ref.phi;
        worstNormal = std::max(worstNormal, (g - expected).norm());
        CHECK((g - expected).norm() <= kNormalTol<S>);
      }
    }
  }
  INFO("worst |phi - reference| " << worstPhi << ", worst normal error " << worstNormal);
  CHECK(worstPhi <= kPhiTol<S>);
}

TEMPLATE_TEST_CASE("convex hull: the culling bound is below phi everywhere, and within sqrt(eps) x size inside",
                   "[convexsdf]", float, double) {
  using S = TestType;
  int inside = 0, outside = 0;
  for (const auto& hc : hulls()) {
    INFO(hc.name);
    const auto sdf = unposed<S>(hc.hull);
    double size = 0;  // the hull's size as the field measures it: its largest vertex coordinate
    for (const Vec& a : hc.hull.vertices()) size = std::max(size, a.cwiseAbs().maxCoeff());
    const S slack = std::sqrt(std::numeric_limits<S>::epsilon()) * S(size);
    for (const Vec& x : hullPoints(hc.hull, 4000, 11)) {
      const drape::Vec3<S> p = x.cast<S>();
      drape::Vec3<S> g;
      const S phi = sdf(p, g);
      const S bound = sdf.lowerBound(p);
      INFO("point " << x.transpose() << ": phi " << phi << ", bound " << bound);
      CHECK(bound < phi);
      if (phi <= S(0)) {  // inside, phi is the nearest face's plane: the largest plane distance
        CHECK(phi - bound <= S(1.01) * slack);
        ++inside;
      } else {
        ++outside;
      }
    }
  }
  CHECK(inside > 1000);
  CHECK(outside > 1000);
}

TEMPLATE_TEST_CASE("the hull of a box's corners is Sdf<Box>, posed or not", "[convexsdf]", float, double) {
  using S = TestType;
  const Vec half(0.4, 0.3, 0.2);
  const ConvexHull& hull = hulls()[1].hull;
  REQUIRE(hull.shift().norm() < 1e-12);  // a box's centre of mass is its centre: the frames agree
  double worst = 0;
  for (const Pose& pose : {Pose{}, genericPose()}) {
    const Vec origin = pose.position.isZero() ? Vec::Zero() : kOrigin;
    const auto fromHull = detail::compileSdf<S>(hull, pose, origin);
    const auto box = detail::compileSdf<S>(Box{half}, pose, origin);
    std::mt19937_64 rng(23);
    for (int i = 0; i < 20000; ++i) {
      // Half the points within 10% of the surface.
      Vec p = randomInBox(rng, -2 * half, 2 * half);
      if (i % 2) {
        const double r = 0.1 * uniform(rng, -1, 1) * half.norm();
        p = p.cwiseMax(-half).cwiseMin(half) + r * randomUnit(rng);
      }
      const Vec x = pose.apply(p) - origin;
      Vec gh, gb;
      const double phiHull = sampleAt(fromHull, x, &gh), phiBox = sampleAt(box, x, &gb);
      INFO("body point " << p.transpose());
      worst = std::max(worst, std::abs(phiHull - phiBox));
      CHECK(std::abs(phiHull - phiBox) <= 2 * kPhiTol<S>);
      // Same normal where it is unique: outside, or inside with one face nearest by a margin.
      const Vec excess = (p.cwiseAbs() - half).eval();
      Vec sorted = excess;
      std::sort(sorted.data(), sorted.data() + 3);
      if (std::abs(phiBox) > kClear && (phiBox > 0 || sorted[2] - sorted[1] > kClear))
        CHECK((gh - gb).norm() <= kNormalTol<S>);
    }
  }
  INFO("worst |phi_hull - phi_box| " << worst);
  CHECK(worst <= 2 * kPhiTol<S>);
}

// --- Normals -------------------------------------------------------------------------------------------------

TEMPLATE_TEST_CASE("normals are unit and equal the finite-difference gradient away from edges, rims, axis and medial "
                   "surface",
                   "[convexsdf]", float, double) {
  using S = TestType;
  const double h = kFloat<S> ? 0x1p-10 : 0x1p-23;  // powers of two: x +- h is exact near 1
  // Outside, the gradient of the distance to a convex set changes by at most |dx| / phi, so a central difference
  // is off by at most h / (2 (phi - h)) per component, plus the rounding of two values of phi over 2h. Inside,
  // with one nearest piece over the whole stencil, phi is linear there (or, beside the axis, nearly so).
  auto bound = [&](double phi) {
    const double rounding = 2 * kPhiTol<S> / (2 * h);
    return std::sqrt(3.0) * (rounding + (phi > 0 ? h / (2 * (phi - h)) : 0.0));
  };
  auto smooth = [&](const Reference& ref) {
    return ref.phi > 0.05 || (ref.phi < -10 * h && ref.gap > 10 * h);
  };
  double worst = 0;  // error / bound
  int checked = 0;
  for (const auto& c : cylinders()) {
    const auto sdf = unposed<S>(c);
    for (const Vec& x : cylinderPoints(c, 3000, 31)) {
      const Vec p = rounded<S>(x);
      const Reference ref = cylinderReference(c, p);
      if (!smooth(ref) || p.head<2>().norm() < 0.05) continue;  // near the axis the radial direction turns fast
      Vec g;
      sampleAt(sdf, p, &g);
      const Vec fd = finiteDifference(sdf, p, h);
      INFO("cylinder " << c.radius << " x " << c.halfHeight << ", point " << p.transpose() << ": normal "
                       << g.transpose() << ", finite difference " << fd.transpose());
      worst = std::max(worst, (g - fd).norm() / bound(ref.phi));
      CHECK((g - fd).norm() <= bound(ref.phi));
      ++checked;
    }
  }
  for (const auto& hc : hulls()) {
    const auto sdf = unposed<S>(hc.hull);
    for (const Vec& x : hullPoints(hc.hull, 3000, 37)) {
      const Vec p = rounded<S>(x);
      const Reference ref = hullReference(hc.hull, p);
      if (!smooth(ref)) continue;
      Vec g;
      sampleAt(sdf, p, &g);
      const Vec fd = finiteDifference(sdf, p, h);
      INFO(hc.name << ", point " << p.transpose() << ": normal " << g.transpose() << ", finite difference "
                   << fd.transpose());
      worst = std::max(worst, (g - fd).norm() / bound(ref.phi));
      CHECK((g - fd).norm() <= bound(ref.phi));
      ++checked;
    }
  }
  INFO(checked << " points, worst |normal - finite difference| " << worst << " of its bound");
  CHECK(checked > 10000);
  CHECK(worst <= 1);
}

TEMPLATE_TEST_CASE("on rims, edges, vertices and the axis the normal is unit and an outward normal of the shape there",
                   "[convexsdf]", float, double) {
  using S = TestType;
  const double eps = std::numeric_limits<S>::epsilon();

  SECTION("cylinder rims and axis") {
    const Cylinder c{0.375, 0.625};  // exact in float
    const auto sdf = unposed<S>(c);
    for (const Vec& radial : {Vec(1, 0, 0), Vec(0, -1, 0), Vec(-1, 0, 0)})
      for (double sz : {-1.0, 1.0}) {
        Vec g;
        const Vec rim = c.radius * radial + Vec(0, 0, sz * c.halfHeight);
        CHECK(sampleAt(sdf, rim, &g) == 0);
        CHECK((g - (radial + Vec(0, 0, sz)) / std::sqrt(2.0)).norm() <= 4 * eps);  // the rim's bisector
      }
    std::mt19937_64 rng(41);
    for (int i = 0; i < 200; ++i) {  // rounded rim points: a normal of the side, a cap, or in between
      const double a = uniform(rng, 0, 2 * std::numbers::pi);
      const Vec radial(std::cos(a), std::sin(a), 0);
      const double sz = i % 2 ? 1 : -1;
      const Vec p = rounded<S>(c.radius * radial + Vec(0, 0, sz * c.halfHeight));
      Vec g;
      CHECK(std::abs(sampleAt(sdf, p, &g)) <= 4 * eps);
      CHECK(std::abs(g.norm() - 1) <= 4 * eps);
      CHECK(g.dot(radial) >= -4 * eps);
      CHECK(g.z() * sz >= -4 * eps);
      CHECK(std::abs(g.dot(Vec(-radial.y(), radial.x(), 0))) <= 1e-3);  // no sideways part
    }
    // On the axis: the nearer cap's normal, or (mid-height, where the side is nearer) a radial direction.
    Vec g = Vec::Zero();
    CHECK(sampleAt(sdf, Vec(0, 0, 0.5), &g) == Approx(-0.125).margin(4 * eps));
    CHECK((g - Vec(0, 0, 1)).norm() <= 4 * eps);
    CHECK(sampleAt(sdf, Vec(0, 0, -0.5), &g) == Approx(-0.125).margin(4 * eps));
    CHECK((g - Vec(0, 0, -1)).norm() <= 4 * eps);
    CHECK(sampleAt(sdf, Vec(0, 0, 0.125), &g) == Approx(-0.375).margin(4 * eps));
    CHECK(std::abs(g.norm() - 1) <= 4 * eps);
    CHECK(std::abs(g.z()) <= 4 * eps);
    CHECK(sampleAt(sdf, Vec(0, 0, 0.75), &g) == Approx(0.125).margin(4 * eps));
    CHECK((g - Vec(0, 0, 1)).norm() <= 4 * eps);
  }

  SECTION("hull vertices, edges and faces, and points just off them") {
    std::mt19937_64 rng(43);
    constexpr double kFrontSlack = 4;
    double worstFront = -1;
    for (const auto& hc : hulls()) {
      INFO(hc.name);
      const auto sdf = unposed<S>(hc.hull);
      const auto& v = hc.hull.vertices();
      double size = 0;
      for (const Vec& w : v) size = std::max(size, w.cwiseAbs().maxCoeff());
      std::vector<Vec> points;
      for (const auto& f : hc.hull.faces()) {
        Vec centre = Vec::Zero();
        for (std::size_t k = 0; k < f.vertices.size(); ++k) {
          const Vec& a = v[f.vertices[k]];
          const Vec& b = v[f.vertices[(k + 1) % f.vertices.size()]];
          centre += a / double(f.vertices.size());
          points.push_back(a);
          points.push_back((a + b) / 2);
          points.push_back(a + uniform(rng, 0, 1) * (b - a));
        }
        points.push_back(centre);
      }
      const std::size_t onSurface = points.size();
      for (std::size_t i = 0; i < onSurface; ++i) {  // just off: rounding's distance up to 1000 times it
        const double r = std::pow(10.0, uniform(rng, 0, 3)) * eps;
        points.push_back(points[i] + r * randomUnit(rng));
      }
      for (std::size_t i = 0; i < points.size(); ++i) {
        const Vec p = rounded<S>(points[i]);
        Vec g;
        const double phi = sampleAt(sdf, p, &g);
        INFO("point " << p.transpose() << ", phi " << phi << ", normal " << g.transpose());
        CHECK(std::abs(g.norm() - 1) <= 10 * eps);
        CHECK(std::abs(phi - hullReference(hc.hull, p).phi) <= kPhiTol<S>);
        // The plane through p with normal g supports the hull: no vertex is in front of it (beyond what
        // being phi inside allows). Rounding of order eps * size in p - closest turns the normal by that over
        // phi, where phi is at least sqrt(eps) * size (nearer, the field takes a face's normal).
        double front = -std::numeric_limits<double>::infinity();
        for (const Vec& w : v) front = std::max(front, g.dot(w - p));
        const double unit = eps * size * (1 + size / std::max(std::abs(phi), std::sqrt(eps) * size));
        worstFront = std::max(worstFront, (front - std::max(0.0, -phi)) / unit);
        CHECK(front - std::max(0.0, -phi) <= kFrontSlack * unit);
      }
    }
    INFO("worst vertex in front of the plane through the point: " << worstFront << " eps size (1 + size / phi)");
    CHECK(worstFront <= kFrontSlack);
  }
}

// --- Field properties ----------------------------------------------------------------------------------------

TEMPLATE_TEST_CASE("fields are 1-Lipschitz and convex, and the normal is a subgradient everywhere", "[convexsdf]",
                   float, double) {
  using S = TestType;
  const double tol = kFloat<S> ? 4e-6 : 1e-13;
  std::mt19937_64 rng(53);
  double steepest = -1, worstConvex = -1, worstTangent = -1;
  // band: the hull field's nearSurface (sqrt(eps) times its size), within which outside it takes the normal of
  // the face the point is farthest in front of; that tangent plane is below the field by at most phi there.
  auto check = [&](const auto& sdf, const std::vector<Vec>& points, const std::string& name, double band) {
    INFO(name);
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Vec a = rounded<S>(points[i]);
      // Partners at lengths from 1e-4 to 2 (log-uniform), and other points of the set (far, across the shape).
      const double length = std::pow(10.0, uniform(rng, -4, 0.3));
      const Vec b = rounded<S>(i % 3 ? Vec(a + length * randomUnit(rng)) : points[(i * 7 + 1) % points.size()]);
      const double len = (b - a).norm();
      if (len == 0) continue;
      Vec ga;
      const double pa = sampleAt(sdf, a, &ga), pb = sampleAt(sdf, b);
      const double mid = sampleAt(sdf, rounded<S>((a + b) / 2));
      INFO("a " << a.transpose() << ", b " << b.transpose() << ": phi " << pa << ", " << pb << ", midpoint " << mid);
      steepest = std::max(steepest, std::abs(pa - pb) - len);
      worstConvex = std::max(worstConvex, mid - (pa + pb) / 2);
      const double allowance = pa > 0 && pa < band ? pa : 0.0;
      worstTangent = std::max(worstTangent, pa + ga.dot(b - a) - pb - allowance);
      CHECK(std::abs(pa - pb) <= len + tol);
      CHECK(mid <= (pa + pb) / 2 + tol);
      CHECK(pb >= pa + ga.dot(b - a) - allowance - tol);  // the tangent plane at a is below the field
    }
  };
  for (const auto& c : cylinders()) {
    std::vector<Vec> points = cylinderPoints(c, 3000, 59);
    // Also on the medial cone (as far from the side as from a cap), the rims and the axis.
    const double m = std::min(c.radius, c.halfHeight);
    for (int i = 0; i < 300; ++i) {
      const double a = uniform(rng, 0, 2 * std::numbers::pi), d = uniform(rng, 0, m);
      const Vec radial(std::cos(a), std::sin(a), 0);
      const double sz = i % 2 ? 1 : -1;
      points.push_back((c.radius - d) * radial + Vec(0, 0, sz * (c.halfHeight - d)));
      points.push_back(c.radius * radial + Vec(0, 0, sz * c.halfHeight));
      points.push_back(Vec(0, 0, uniform(rng, -1.5, 1.5) * c.halfHeight));
    }
    check(unposed<S>(c), points, "cylinder " + std::to_string(c.radius) + " x " + std::to_string(c.halfHeight), 0.0);
  }
  for (const auto& hc : hulls()) {
    std::vector<Vec> points = hullPoints(hc.hull, 3000, 61);
    for (const Vec& w : hc.hull.vertices()) points.push_back(w);
    // Inside points as near two face planes as each other.
    const auto& faces = hc.hull.faces();
    for (int i = 0; i < 300; ++i) {
      const Vec p = hullPoints(hc.hull, 1, 67 + i)[0] * 0.5;
      const auto& f0 = faces[std::size_t(i) % faces.size()];
      const auto& f1 = faces[std::size_t(i * 5 + 1) % faces.size()];
      const double s0 = f0.normal.dot(p - hc.hull.vertices()[f0.vertices[0]]);
      const double s1 = f1.normal.dot(p - hc.hull.vertices()[f1.vertices[0]]);
      const Vec dn = f0.normal - f1.normal;
      if (dn.squaredNorm() > 1e-6) points.push_back(p - (s0 - s1) / dn.squaredNorm() * dn);
    }
    const auto sdf = unposed<S>(hc.hull);
    check(sdf, points, hc.name, double(sdf.hull->nearSurface));
  }
  INFO("worst |phi(a) - phi(b)| - |a - b| " << steepest << ", worst midpoint excess " << worstConvex
                                              << ", worst tangent excess " << worstTangent);
  CHECK(steepest <= tol);
  CHECK(worstConvex <= tol);
  CHECK(worstTangent <= tol);
}

TEMPLATE_TEST_CASE("a posed field is the unposed one at the point taken into the body frame", "[convexsdf]", float,
                   double) {
  using S = TestType;
  const Pose pose = genericPose();
  // Rounding of the world point (a few metres from the origin) and of the turn.
  const double phiTol = kFloat<S> ? 1e-5 : 1e-13, normalTol = kFloat<S> ? 1e-4 : 1e-10;
  double worstPhi = 0, worstNormal = 0;
  auto check = [&](const auto& shape, const std::vector<Vec>& points, auto reference) {
    const auto posed = detail::compileSdf<S>(shape, pose, kOrigin);
    const auto local = unposed<S>(shape);
    for (const Vec& x : points) {
      const Vec p = rounded<S>(x);
      Vec gp, gl;
      const double phiPosed = sampleAt(posed, pose.apply(p) - kOrigin, &gp);
      const double phiLocal = sampleAt(local, p, &gl);
      INFO("body point " << p.transpose() << ": posed " << phiPosed << ", unposed " << phiLocal);
      worstPhi = std::max(worstPhi, std::abs(phiPosed - phiLocal));
      CHECK(std::abs(phiPosed - phiLocal) <= phiTol);
      const Reference ref = reference(p);
      if (ref.phi > kClear || (ref.phi < -kClear && ref.gap > kClear && (p.head<2>().norm() > kClear))) {
        worstNormal = std::max(worstNormal, (gp - pose.rotation * gl).norm());
        CHECK((gp - pose.rotation * gl).norm() <= normalTol);
      }
    }
  };
  for (const auto& c : cylinders())
    check(c, cylinderPoints(c, 2000, 71), [&](const Vec& p) { return cylinderReference(c, p); });
  for (const auto& hc : hulls())
    check(hc.hull, hullPoints(hc.hull, 2000, 73), [&](const Vec& p) { return hullReference(hc.hull, p); });
  INFO("worst |posed - unposed| " << worstPhi << ", worst normal difference " << worstNormal);
  CHECK(worstPhi <= phiTol);
}

}  // namespace convex_sdf_tests
