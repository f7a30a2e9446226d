// The convex hull builder (drape/shapes/convex_hull.hpp) against its definition, with no code shared with it:
// every hull vertex is an input point, every input point is behind every face's plane, the faces are planar
// convex polygons that close into a surface of Euler characteristic 2, neighbouring faces are not coplanar, and
// the volume is that of the faces. Checked on the point sets that break builders whose decisions depend on
// rounding: many coplanar and collinear points, duplicates, turned and moved copies, and the same sets with
// every coordinate nudged by a few ulps (what a build that fuses multiply-adds does to a builder's arithmetic).
#include <drape/shapes/convex_hull.hpp>

#include <catch2/catch.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

// Each test source keeps its helpers in a namespace of its own: the tests build as unity batches.
namespace convex_hull_tests {

namespace {

using namespace drape;
using Vec = Eigen::Vector3d;

struct PointSet {
  std::string name;
  std::vector<Vec> points;
};

/// The faults of `hull` as the hull of `points`, one line each; empty if there is none. Lengths are compared
/// within `tolerance` times the points' extent.
std::vector<std::string> hullFaults(const std::vector<Vec>& points, const ConvexHull& hull, double tolerance) {
  std::vector<std::string> faults;
  auto fault = [&](const std::string& s) {
    if (faults.size() < 10) faults.push_back(s);
  };
  Vec lo = points[0], hi = points[0];
  for (const Vec& p : points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double tol = tolerance * (hi - lo).norm();
  const auto& v = hull.vertices();
  const Vec shift = hull.shift();

  for (std::size_t i = 0; i < v.size(); ++i) {  // every vertex is an input point (to rounding of the shift)
    double nearest = std::numeric_limits<double>::infinity();
    for (const Vec& p : points) nearest = std::min(nearest, (v[i] + shift - p).norm());
    if (nearest > 1e-12 * (hi - lo).norm()) fault("vertex " + std::to_string(i) + " is no input point");
  }
  std::map<std::pair<int, int>, int> edgeCount;
  std::vector<char> used(v.size(), 0);
  double volume = 0;
  for (std::size_t f = 0; f < hull.faces().size(); ++f) {
    const auto& face = hull.faces()[f];
    const std::string name = "face " + std::to_string(f);
    const int n = static_cast<int>(face.vertices.size());
    if (n < 3) {
      fault(name + " has " + std::to_string(n) + " vertices");
      continue;
    }
    if (std::abs(face.normal.norm() - 1) > 1e-12) fault(name + "'s normal is not unit");
    Vec mean = Vec::Zero();
    for (int i : face.vertices) mean += v[i], used[i] = 1;
    mean /= n;
    const double offset = face.normal.dot(mean);
    for (int i : face.vertices)
      if (std::abs(face.normal.dot(v[i]) - offset) > tol)
        fault(name + " is not planar: vertex " + std::to_string(i) + " is " +
              std::to_string(face.normal.dot(v[i]) - offset) + " m off its plane");
    for (std::size_t i = 0; i < points.size(); ++i)
      if (face.normal.dot(points[i] - shift) - offset > tol)
        fault("point " + std::to_string(i) + " is in front of " + name + " by " +
              std::to_string(face.normal.dot(points[i] - shift) - offset));
    for (int k = 0; k < n; ++k) {  // convex, counter-clockwise about the normal
      const Vec& a = v[face.vertices[k]];
      const Vec& b = v[face.vertices[(k + 1) % n]];
      const Vec& c = v[face.vertices[(k + 2) % n]];
      const double turn = (b - a).cross(c - b).dot(face.normal) / (c - a).norm();  // b's distance from ac
      if (turn < -tol)
        fault(name + " is not convex: vertex " + std::to_string(face.vertices[(k + 1) % n]) + " is " +
              std::to_string(-turn) + " m inside the line of its neighbours");
      ++edgeCount[{face.vertices[k], face.vertices[(k + 1) % n]}];
      volume += a.dot(b.cross(mean)) / 6;  // a fan from the mean: the divergence theorem
    }
  }
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!used[i]) fault("vertex " + std::to_string(i) + " is on no face");
  for (const auto& [edge, count] : edgeCount) {
    const auto twin = edgeCount.find({edge.second, edge.first});
    if (count != 1 || twin == edgeCount.end() || twin->second != 1)
      fault("edge " + std::to_string(edge.first) + "-" + std::to_string(edge.second) + " is not shared by two faces");
  }
  const long euler = long(v.size()) - long(edgeCount.size() / 2) + long(hull.faces().size());
  if (euler != 2) fault("Euler characteristic " + std::to_string(euler));
  // Neighbouring faces are not coplanar: some vertex of one is off the other's plane.
  std::map<std::pair<int, int>, int> faceOf;
  for (std::size_t f = 0; f < hull.faces().size(); ++f) {
    const auto& vs = hull.faces()[f].vertices;
    for (std::size_t k = 0; k < vs.size(); ++k) faceOf[{vs[k], vs[(k + 1) % vs.size()]}] = int(f);
  }
  for (const auto& [edge, f] : faceOf) {
    const auto twin = faceOf.find({edge.second, edge.first});
    if (twin == faceOf.end() || twin->second < f) continue;
    const auto& a = hull.faces()[std::size_t(f)];
    const auto& b = hull.faces()[std::size_t(twin->second)];
    bool off = false;
    for (int i : b.vertices) off = off || std::abs(a.normal.dot(v[i] - v[a.vertices[0]])) > tol;
    if (!off) fault("faces " + std::to_string(f) + " and " + std::to_string(twin->second) + " are coplanar");
  }
  if (std::abs(volume - hull.volume()) > 1e-9 * std::abs(volume))
    fault("volume " + std::to_string(hull.volume()) + " is not the faces' " + std::to_string(volume));
  return faults;
}

Vec turned(const Vec& p) {  // a rotation about an oblique axis and a move: no coordinate stays round
  static const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, Vec(1, 2, 3).normalized()).toRotationMatrix();
  return r * p + Vec(0.31, -1.7, 2.9);
}

std::vector<PointSet> pointSets() {
  std::vector<PointSet> out;
  std::vector<Vec> prism, cube, cylinder, slab;
  for (int k = 0; k < 6; ++k) {
    const double a = k * std::numbers::pi / 3;
    for (double z : {-0.3, 0.3}) prism.emplace_back(0.5 * std::cos(a), 0.5 * std::sin(a), z);
  }
  out.push_back({"hexagonal prism", prism});
  for (int i = 0; i <= 4; ++i)  // a 5 x 5 grid on each face of a cube: coplanar and collinear points
    for (int j = 0; j <= 4; ++j)
      for (int axis = 0; axis < 3; ++axis)
        for (double side : {-0.5, 0.5}) {
          Vec p;
          p[axis] = side, p[(axis + 1) % 3] = -0.5 + 0.25 * i, p[(axis + 2) % 3] = -0.5 + 0.25 * j;
          cube.push_back(p);
        }
  out.push_back({"grid on a cube's faces", cube});
  for (int k = 0; k < 48; ++k) {  // two 48-gons and points along the side's lines
    const double a = 2 * std::numbers::pi * k / 48;
    for (double z : {-0.4, -0.1, 0.2, 0.4}) cylinder.emplace_back(0.3 * std::cos(a), 0.3 * std::sin(a), z);
  }
  out.push_back({"cylinder with rings", cylinder});
  for (int k = 0; k < 8; ++k) {
    const double a = k * std::numbers::pi / 4 + 0.1;
    for (double z : {-0.04, 0.04}) slab.emplace_back(0.6 * std::cos(a), 0.5 * std::sin(a), z);
  }
  out.push_back({"thin octagonal slab", slab});
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<Vec> filled = cube;  // the grid, its points twice, and points inside
  filled.insert(filled.end(), cube.begin(), cube.end());
  for (int i = 0; i < 100; ++i) {
    const double x = u(rng), y = u(rng), z = u(rng);
    filled.emplace_back(x, y, z);
  }
  std::shuffle(filled.begin(), filled.end(), rng);
  out.push_back({"grid twice with points inside, shuffled", filled});
  std::vector<Vec> sphere;
  std::normal_distribution<double> g(0, 1);
  for (int i = 0; i < 300; ++i) {
    const double x = g(rng), y = g(rng), z = g(rng);
    sphere.push_back(0.4 * Vec(x, y, z).normalized());
  }
  out.push_back({"300 points on a sphere", sphere});

  const std::size_t plain = out.size();
  for (std::size_t s = 0; s < plain; ++s) {
    std::vector<Vec> t;
    for (const Vec& p : out[s].points) t.push_back(turned(p));
    out.push_back({out[s].name + ", turned and moved", t});
  }
  const std::size_t unnudged = out.size();
  for (std::size_t s = 0; s < unnudged; ++s)
    for (int seed = 1; seed <= 3; ++seed) {  // each coordinate moved by up to 4 ulps
      std::mt19937_64 r(std::uint64_t(seed) * 977 + s);
      std::uniform_int_distribution<int> ulps(-4, 4);
      std::vector<Vec> t = out[s].points;
      for (Vec& p : t)
        for (int a = 0; a < 3; ++a)
          for (int k = ulps(r); k != 0; k += k > 0 ? -1 : 1)
            p[a] = std::nextafter(p[a], k > 0 ? 1e300 : -1e300);
      out.push_back({out[s].name + ", nudged (seed " + std::to_string(seed) + ")", t});
    }
  return out;
}

/// The determinant's sign from integer coordinates, exactly (|coordinates| < 2^40: the products fit 128 bits).
__extension__ typedef __int128 Int128;  // (a GCC and Clang extension; __extension__ keeps -Wpedantic quiet)

int exactSign(const Vec& a, const Vec& b, const Vec& c, const Vec& p) {
  auto i = [](double x) { return static_cast<Int128>(x); };
  const Int128 ux = i(b.x()) - i(a.x()), uy = i(b.y()) - i(a.y()), uz = i(b.z()) - i(a.z());
  const Int128 vx = i(c.x()) - i(a.x()), vy = i(c.y()) - i(a.y()), vz = i(c.z()) - i(a.z());
  const Int128 wx = i(p.x()) - i(a.x()), wy = i(p.y()) - i(a.y()), wz = i(p.z()) - i(a.z());
  const Int128 det = ux * (vy * wz - vz * wy) + uy * (vz * wx - vx * wz) + uz * (vx * wy - vy * wx);
  return det > 0 ? 1 : (det < 0 ? -1 : 0);
}

}  // namespace

TEST_CASE("convex hull: the orientation of a point to a plane is exact where rounding gets it wrong",
          "[convexhull]") {
  // Integer points (exact in double): a triangle with two nearly parallel edges u and v = 2u + e, and a
  // point p = a + s u + t v + a nudge of -1, 0 or 1 per coordinate. The products are near 2^111, the
  // determinant (u x e) . nudge near 2^44: rounded, its sign is noise.
  std::mt19937_64 rng(3);
  std::uniform_int_distribution<std::int64_t> big(-(std::int64_t(1) << 36), std::int64_t(1) << 36);
  std::uniform_int_distribution<int> nudge(-1, 1), small(-3, 3), edge(-256, 256);
  auto vec = [&](auto& dist) {
    const double x = double(dist(rng)), y = double(dist(rng)), z = double(dist(rng));
    return Vec(x, y, z);
  };
  int wrongWhenRounded = 0, zeros = 0;
  const int cases = 20000;
  for (int trial = 0; trial < cases; ++trial) {
    const Vec a = vec(big), u = vec(big), e = vec(edge);
    const double s = small(rng), t = small(rng);
    const Vec b = a + u, c = a + 2 * u + e, p = a + s * u + t * (2 * u + e) + vec(nudge);
    const int exact = exactSign(a, b, c, p);
    zeros += exact == 0;
    // The same sign from each of the triangle's three starting vertices.
    CHECK(detail::orientation(a, b, c, p) == exact);
    CHECK(detail::orientation(b, c, a, p) == exact);
    CHECK(detail::orientation(c, a, b, p) == exact);
    const Vec f = b - a, g = c - a, h = p - a;
    const double rounded = f.x() * (g.y() * h.z() - g.z() * h.y()) + f.y() * (g.z() * h.x() - g.x() * h.z()) +
                           f.z() * (g.x() * h.y() - g.y() * h.x());
    wrongWhenRounded += (rounded > 0 ? 1 : (rounded < 0 ? -1 : 0)) != exact;
  }
  INFO(zeros << " of " << cases << " exactly on the plane, " << wrongWhenRounded << " wrong when rounded");
  CHECK(zeros > cases / 40);           // the nudge is zero in 1 of 27 cases
  CHECK(wrongWhenRounded > cases / 4);  // the cases are hard
}

TEST_CASE("convex hull: the hull of coplanar, collinear, repeated and nudged points is their hull", "[convexhull]") {
  int faulty = 0;
  for (const PointSet& set : pointSets()) {
    INFO(set.name << " (" << set.points.size() << " points)");
    const ConvexHull hull(set.points);
    const auto faults = hullFaults(set.points, hull, 1e-9);
    for (const auto& f : faults) UNSCOPED_INFO(f);
    CHECK(faults.empty());
    faulty += !faults.empty();
  }
  CHECK(faulty == 0);
}

}  // namespace convex_hull_tests
