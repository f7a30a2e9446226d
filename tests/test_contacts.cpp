// The contact buffer and the settle onto contact planes (collision/response.hpp), at the level of one vertex:
// what a vertex touching more surfaces than it has slots for may and may not be moved to, and where a pinched
// vertex's least-squares compromise puts it; where the true fields refuse its exact point, and what that does in the
// heavy brick's pinch.
#include <drape/drape.hpp>

#include <Eigen/Eigenvalues>
#include <catch2/catch.hpp>

#include "edge_press.hpp"
#include "heavy_brick.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numbers>
#include <random>
#include <tuple>
#include <type_traits>
#include <vector>

namespace {

/// A vertex where two faces of a box (pressing down) and an upward-facing face of a second body meet in a thin
/// wedge over the floor (z = 0): the surfaces of the seed-1 rain's vertex that the settle drove 1.4 m below
/// the floor (`rigid_rain --bodies 80 --seed 1`, step 99, shifted so the floor is at z = 0). The vertex sits
/// on the floor, 4.7 and 4.4 mm behind the box's two faces.
template <class S> struct Wedge {
  const drape::Vec3<S> x0{S(0.228752), S(-0.173995), S(0)};
  const drape::Vec3<S> n[3] = {drape::Vec3<S>(S(0.47477), S(0.119988), S(-0.871892)).normalized(),
                          drape::Vec3<S>(S(0.306407), S(0.48863), S(-0.816918)).normalized(),
                          drape::Vec3<S>(S(-0.599388), S(-0.175908), S(0.780891)).normalized()};
  const S behind[3] = {S(0.0047), S(0.0044), S(0)};  // how far x0 is behind each plane
  drape::SolidMotion<S> still{drape::Vec3<S>::Zero(), drape::Vec3<S>::Zero(), drape::Vec3<S>::Zero(), S(0), S(0), -1};

  /// The three faces recorded for the vertex (the contacts' placements put x0 `behind` each plane), and the
  /// floor too when `floor`: its normal is within no slot's merge angle, and the slots are full.
  drape::ContactBuffer<S> record(bool floor) const {
    drape::ContactBuffer<S> buffer;
    buffer.resize(1);
    buffer.begin();
    for (int k = 0; k < 3; ++k) {
      const drape::Vec3<S> placed = x0 + behind[k] * n[k];
      buffer.template record<false>(0, placed, n[k], behind[k], still, placed, still.velocityAt(placed));
    }
    if (floor) buffer.template record<false>(0, x0, drape::Vec3<S>::UnitZ(), S(0), still, x0, still.velocityAt(x0));
    return buffer;
  }
  /// Where the settle puts the vertex.
  drape::Vec3<S> settle(const drape::ContactBuffer<S>& buffer) const {
    drape::Vec3<S> x = x0, reference = x0, binned = x0;
    drape::projectOntoContactPlanes(0, 1, buffer, &x, &reference, &binned);
    return x;
  }
};

}  // namespace

TEMPLATE_TEST_CASE("the settle never places a vertex behind a surface that found its slots full", "[contacts]", float,
                   double) {
  using S = TestType;
  const Wedge<S> wedge;
  // The three faces alone: the nearest point outside all three is their corner, 1.8 cm below the floor. That is
  // right for those planes, and shows what the floor's record must prevent.
  const auto without = wedge.record(false);
  CHECK(int(without.slotCount[0]) == 3);
  const drape::Vec3<S> corner = wedge.settle(without);
  CHECK(corner.z() < S(-0.01));
  // With the floor: it joined the closest slot (the second body's face, whose normal it keeps), so the planes do
  // not hold it; the vertex stays on the floor for the passes on the true fields.
  const auto with = wedge.record(true);
  CHECK(int(with.slotCount[0]) == 3);
  CHECK(with.overflow[0] == with.current);
  const drape::Vec3<S> settled = wedge.settle(with);
  CHECK(settled.z() >= S(0));
}

TEMPLATE_TEST_CASE("a surface facing away from every recorded one keeps a slot, and the response answers it",
                   "[contacts]", float, double) {
  // Three faces of a body's corner pressing a vertex down, then the floor under it (the rain's vertices that went
  // 4-9 mm into the floor, `rigid_rain --bodies 80`, seeds 1-3). Joined to the closest face, the floor was lost:
  // nothing kept the vertex's velocity from carrying it into the floor.
  using S = TestType;
  using V = drape::Vec3<S>;
  const V n[3] = {V(S(0.3), S(0.1), S(-0.95)).normalized(), V(S(-0.2), S(0.35), S(-0.9)).normalized(),
                  V(S(0.05), S(-0.4), S(-0.9)).normalized()};
  const S dn[3] = {S(0.004), S(0.003), S(0.002)};
  drape::SolidMotion<S> still{V::Zero(), V::Zero(), V::Zero(), S(0), S(0), -1};
  const V x0(S(0.1), S(-0.2), S(0.003));
  drape::ContactBuffer<S> buffer;
  buffer.resize(1);
  buffer.begin();
  for (int k = 0; k < 3; ++k) buffer.template record<false>(0, x0, n[k], dn[k], still, x0, V::Zero());
  REQUIRE(int(buffer.slotCount[0]) == 3);
  // The two closest faces: they will share a slot.
  int keep = 0, give = 1;
  for (int j = 0; j < 3; ++j)
    for (int k = j + 1; k < 3; ++k)
      if (n[j].dot(n[k]) > n[keep].dot(n[give])) keep = j, give = k;
  buffer.template record<false>(0, x0, V::UnitZ(), S(0.001), still, x0, V::Zero());
  CHECK(buffer.overflow[0] == buffer.current);
  CHECK(int(buffer.slotCount[0]) == 3);
  CHECK(buffer.slots[0][std::size_t(give)].normal == V::UnitZ());
  CHECK(buffer.slots[0][std::size_t(keep)].normal == n[keep]);
  CHECK(buffer.slots[0][std::size_t(keep)].correction == dn[keep] + dn[give]);
  // A vertex driven down into the floor between them stops: its velocity approaches none of the recorded
  // surfaces (the face that gave up its slot is not among them).
  V x = x0, xPrev = x0, v(S(0.1), S(0), S(-1));
  drape::respondContacts<false>(0, 1, buffer, &x, &xPrev, &v, S(1) / S(600), S(0));
  CHECK(v.z() >= S(0));
  for (int k = 0; k < 3; ++k) CHECK(buffer.slots[0][std::size_t(k)].normal.dot(v) >= -S(1e-6));
  // A fourth direction near the others still joins the closest: the first three seen stay.
  drape::ContactBuffer<S> near;
  near.resize(1);
  near.begin();
  for (int k = 0; k < 3; ++k) near.template record<false>(0, x0, n[k], dn[k], still, x0, V::Zero());
  const V side = V(S(0.6), S(0.3), S(-0.75)).normalized();
  near.template record<false>(0, x0, side, S(0.001), still, x0, V::Zero());
  for (int k = 0; k < 3; ++k) CHECK(near.slots[0][std::size_t(k)].normal == n[k]);
  // But where the three are one coupled body's faces and a direction from another solid is further from each of
  // them than the body's two closest faces are from each other, those share a slot: a slot mixes one body's faces
  // rather than two solids.
  drape::ContactBuffer<S> bodies;
  bodies.resize(1);
  bodies.keepLines(true);
  bodies.begin();
  drape::SolidMotion<S> body = still;
  body.body = 2;
  for (int k = 0; k < 3; ++k) bodies.template record<true>(0, x0, n[k], dn[k], body, x0, V::Zero());
  const V across = V(S(1), S(0), S(0.1)).normalized();  // not facing away from all three (from n[0] 0.3)
  bodies.template record<false>(0, x0, across, S(0.001), still, x0, V::Zero());
  CHECK(bodies.slots[0][std::size_t(give)].normal == across);
  CHECK(bodies.slots[0][std::size_t(give)].body == -1);
  CHECK(bodies.slots[0][std::size_t(keep)].correction == dn[keep] + dn[give]);
}

TEMPLATE_TEST_CASE("the eigen-decomposition of a 3x3 normal matrix agrees with Eigen's", "[contacts]", float, double) {
  using S = TestType;
  // symmetricEigen3 (and its GLSL twin) against Eigen's solver, on sums of one to three outer products of unit
  // normals (what the least-squares compromise decomposes), including nearly facing and nearly equal pairs.
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  // Float: a few roundings of entries up to 3. Double: the rotations leave an off-diagonal entry up to
  // kEigenNegligible times its diagonal pair's sum (at most 6).
  const double tolerance = std::is_same_v<S, float> ? 2e-5 : 10 * drape::constants::kEigenNegligible * 3;
  double worst = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const int count = 1 + trial % 3;
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
    drape::Vec3<S> n0 = drape::Vec3<S>::Zero();
    for (int k = 0; k < count; ++k) {
      Eigen::Vector3d n(g(rng), g(rng), g(rng));
      if (k == 1 && trial % 4 == 1) n = -n0.template cast<double>() + 0.05 * n.normalized();  // nearly facing
      if (k == 1 && trial % 4 == 3) n = n0.template cast<double>() + 0.01 * n.normalized();   // nearly equal
      const drape::Vec3<S> ns = n.normalized().cast<S>();
      if (k == 0) n0 = ns;
      m += ns.template cast<double>() * ns.template cast<double>().transpose();
    }
    S a[3][3], v[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) a[i][j] = S(m(i, j));
    drape::symmetricEigen3(a, v);
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> reference(m);
    double values[3] = {double(a[0][0]), double(a[1][1]), double(a[2][2])};
    std::sort(values, values + 3);
    for (int i = 0; i < 3; ++i) worst = std::max(worst, std::abs(values[i] - reference.eigenvalues()[i]));
    for (int i = 0; i < 3; ++i) {  // m e = lambda e, and e of unit length
      const Eigen::Vector3d e(double(v[0][i]), double(v[1][i]), double(v[2][i]));
      worst = std::max(worst, (m * e - double(a[i][i]) * e).norm());
      worst = std::max(worst, std::abs(e.norm() - 1));
      for (int j = 0; j < 3; ++j)
        if (j != i) worst = std::max(worst, std::abs(double(a[i][j])));
    }
  }
  INFO("largest error " << worst);
  CHECK(worst <= tolerance);
}

TEMPLATE_TEST_CASE("a pass of the least-squares compromise is its definition's move, in closed form for one or "
                   "two planes", "[contacts][pinch]", float, double) {
  using S = TestType;
  using V = drape::Vec3<S>;
  // The move is the sum over the eigen-directions e of sum_k n_k n_k^T (the violated planes) whose eigenvalue is at
  // least 1/reach^2 of (e . g / lambda) e, g = sum_k r_k n_k: here in double with Eigen's solver, against the
  // closed forms for one and two violated planes and the Jacobi rotations for three. Nearly facing and nearly
  // equal pairs, pairs whose difference sits near the cut, and points that leave one, two or three planes violated.
  // A trial whose violated set or cut rounding could decide is left out (the two sides may choose differently).
  std::mt19937 rng(11);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(-0.004, 0.004);
  const double reach = drape::constants::kReach, weakest = 1 / (reach * reach);
  // Relative to the violations (at most 8 mm), divided by the weakest eigenvalue kept: float's roundings of the
  // normals' products, and in double the rotations' residue (an off-diagonal entry up to kEigenNegligible).
  const double tolerance = std::is_same_v<S, float> ? 1e-5 : 1e-10;
  double worst = 0;
  int byCount[4] = {}, nearCut = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const int count = 1 + trial % 3;
    V n[3];
    S b[3];
    for (int k = 0; k < count; ++k) {
      Eigen::Vector3d d(g(rng), g(rng), g(rng));
      d.normalize();
      if (k == 1 && trial % 5 == 1) d = (-n[0].template cast<double>() + 0.05 * d).normalized();  // nearly facing
      if (k == 1 && trial % 5 == 3) d = (n[0].template cast<double>() + 0.01 * d).normalized();   // nearly equal
      if (k == 1 && trial % 5 == 4) {  // 1 - cos near 1/reach^2: the difference's eigenvalue near the cut
        const Eigen::Vector3d a = n[0].template cast<double>(), side = a.cross(d).normalized().cross(a);
        const double angle = std::acos(1 - weakest) * (1 + 0.02 * g(rng));
        d = std::cos(angle) * a + std::sin(angle) * side;
      }
      n[k] = d.cast<S>();
      b[k] = S(u(rng));
    }
    const V y(S(u(rng)), S(u(rng)), S(u(rng)));
    const Eigen::Vector3d yd = y.template cast<double>();
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    Eigen::Vector3d gs = Eigen::Vector3d::Zero();
    int violated = 0;
    bool ambiguous = false;
    for (int k = 0; k < count; ++k) {
      const Eigen::Vector3d nk = n[k].template cast<double>();
      const double r = double(b[k]) - nk.dot(yd);
      ambiguous |= std::abs(r) < 1e-6;
      if (r <= 0) continue;
      ++violated;
      gs += r * nk;
      a += nk * nk.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(a);
    Eigen::Vector3d move = Eigen::Vector3d::Zero();
    double smallest = 1;
    for (int i = 0; i < 3; ++i) {
      const double lambda = eigen.eigenvalues()[i];
      ambiguous |= std::abs(lambda - weakest) < 1e-4;
      if (lambda < weakest) continue;
      smallest = std::min(smallest, lambda);
      const Eigen::Vector3d e = eigen.eigenvectors().col(i);
      move += (e.dot(gs) / lambda) * e;
    }
    if (ambiguous) continue;
    ++byCount[violated];
    nearCut += trial % 5 == 4 && violated == 2;
    const V got = drape::leastSquaresMove(n, b, count, y, S(weakest));
    worst = std::max(worst, (got.template cast<double>() - move).norm() * smallest / 0.008);
  }
  INFO("largest difference " << worst << " (of the largest violation, times the weakest eigenvalue kept); points "
                             << "with 0, 1, 2 and 3 planes violated: " << byCount[0] << ", " << byCount[1] << ", "
                             << byCount[2] << ", " << byCount[3] << ", " << nearCut << " pairs near the cut");
  CHECK(byCount[1] > 300);
  CHECK(byCount[2] > 300);
  CHECK(byCount[3] > 100);
  CHECK(nearCut > 50);
  CHECK(worst <= tolerance);
}

TEMPLATE_TEST_CASE("a point pinched between two nearly facing planes goes to the middle of the gap, not sideways",
                   "[contacts][pinch]", float, double) {
  using S = TestType;
  // The floor (z >= 0) and a plane facing down, tilted by 0.11 (a face contact's normal at a box's bottom edge),
  // 4.6 mm apart where the point is: no point is 5 mm from both, and where they meet is 9 mm to the side. The
  // compromise moves the point along the axis between the planes only, to the middle, where both are violated
  // alike. Gradient steps toward their meeting point (16 Jacobi steps, the earlier compromise) moved this point
  // 0.57 mm sideways, and a pinched cloth's rim vertices so every substep.
  const drape::Vec3<S> n[2] = {drape::Vec3<S>(0, 0, 1), drape::Vec3<S>(S(0.043), S(0.103), S(-0.994)).normalized()};
  const drape::Vec3<S> from(S(0.09), S(0.07), S(-0.001));
  const S b[2] = {S(0), n[1].dot(from) + S(0.0003)};  // 1 mm and 0.3 mm violated
  const drape::Vec3<S> y = drape::nearestInHalfSpaces(n, b, 2, from, from);
  const drape::Vec3<S> axis = (n[0] - n[1]).normalized();
  const drape::Vec3<S> move = y - from;
  const S sideways = (move - move.dot(axis) * axis).norm();
  const S r0 = b[0] - n[0].dot(y), r1 = b[1] - n[1].dot(y);
  INFO("moved " << move.norm() << " m, " << sideways << " m of it sideways; violations left " << r0 << ", " << r1);
  CHECK(sideways <= 1e-6);
  CHECK(std::abs(r0 - r1) <= 1e-6);      // balanced: the middle of the gap
  CHECK(r0 == Approx(0.00065).margin(1e-5));  // half the total violation each
}

TEMPLATE_TEST_CASE("a face whose corners sit at the thickness on a flat side is no contact, one a little deeper is",
                   "[contacts]", float, double) {
  // Corners placed at the thickness by their own vertex contacts leave the face's deepest point a few roundings
  // either side of it. Taken as a contact, such a face paid the push, three records and the response for
  // nothing (docs/design.md §3, "Faces at the thickness"): on the resting ridge 1 052 face contacts per substep
  // in float where 39 were deeper. A box turned at random, 1-2 m from the origin; 200 faces of 2 cm on its top.
  using S = TestType;
  using V = drape::Vec3<S>;
  const S thickness = S(0.005);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  int rounding = 0, atThickness = 0, deeper = 0;
  const int faces = 200;
  for (int k = 0; k < faces; ++k) {
    drape::Solid<drape::Box> box;
    box.shape.halfExtents = {0.3, 0.2, 0.1};
    box.pose.rotation = Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized());
    box.pose.position = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized() * (1.5 + 0.5 * u(rng));
    const auto solid = drape::detail::compileSolid<drape::Box, S>(box, Eigen::Vector3d::Zero());
    // A 2 cm face on the top, well inside its edges, its corners half the thickness inside the shell; the vertex
    // pass moves them out to it, as at the start of a resting substep.
    const Eigen::Vector3d centre(0.2 * u(rng), 0.1 * u(rng), 0.1 + 0.5 * double(thickness));
    const double turn = 3.2 * u(rng);
    std::vector<V> x;
    for (int c = 0; c < 3; ++c) {
      const double a = turn + 2.0944 * c;
      const Eigen::Vector3d local = centre + 0.0115 * Eigen::Vector3d(std::cos(a), std::sin(a), 0);
      x.push_back((box.pose.rotation * local + box.pose.position).template cast<S>());
    }
    const std::vector<S> invMass(3, S(1));
    const std::vector<std::array<drape::Index, 3>> triangle = {{0, 1, 2}};
    const drape::Index only = 0;
    drape::ContactBuffer<S> contacts;
    contacts.resize(3);
    contacts.begin();
    drape::projectVertexContacts(0, 3, solid, thickness, x.data(), invMass.data(), drape::AllItems{}, contacts,
                                 x.data());
    drape::FaceQuery<S> q;
    rounding += drape::queryFace<true>(solid.sdf, x[0], x[1], x[2], thickness, 12, q) && q.phi < thickness;
    drape::CollisionStats stats;
    std::vector<V> y = x;
    drape::projectFaceContacts<true>(solid, thickness, 12, triangle, drape::ItemList{&only}, 1, y.data(),
                                     invMass.data(), contacts, stats, y.data());
    atThickness += int(stats.faceContacts);
    // The same face a thousandth of the thickness into the shell is a contact.
    const V in = -(box.pose.rotation * Eigen::Vector3d::UnitZ()).template cast<S>() * (S(1e-3) * thickness);
    for (V& p : x) p += in;
    drape::CollisionStats deeperStats;
    drape::projectFaceContacts<true>(solid, thickness, 12, triangle, drape::ItemList{&only}, 1, x.data(),
                                     invMass.data(), contacts, deeperStats, x.data());
    deeper += int(deeperStats.faceContacts);
  }
  INFO(rounding << " of " << faces << " faces read inside the thickness by rounding, " << atThickness
                << " taken as contacts; " << deeper << " contacts a thousandth of the thickness deeper");
  CHECK(rounding > 0);  // the case the rule is for occurs here
  CHECK(atThickness == 0);
  CHECK(deeper == faces);
}

TEMPLATE_TEST_CASE("the settle takes an exact point only where each of its planes is a solid's surface there",
                   "[contacts]", float, double) {
  // A cloth pinched under a brick's bottom edge (the heavy brick's exit, docs/design.md §16, "Exact points
  // tested"): the floor z = 0 and a box whose bottom face lies at 1.8 thicknesses, its edge along y at x = 0. A
  // vertex 1.5 mm past the edge, inside the floor's thickness and the edge's, has the floor's plane and the edge's
  // tangent; the two meet 2.3 mm further along x, within reach, where the edge's tangent is no longer the box's
  // surface. Taken, that point is a jump along the pull.
  using S = TestType;
  using V = drape::Vec3<S>;
  const S t = S(0.005);
  drape::Solid<drape::Box> brick;
  brick.shape.halfExtents = {0.05, 0.05, 0.02};
  brick.pose.position = {-0.05, 0.0, 1.8 * 0.005 + 0.02};
  using drape::CompiledSolid;
  const std::tuple<std::vector<CompiledSolid<drape::Plane, S>>, std::vector<CompiledSolid<drape::Box, S>>> solids{
      {drape::detail::compileSolid<drape::Plane, S>(drape::Solid<drape::Plane>{}, Eigen::Vector3d::Zero())},
      {drape::detail::compileSolid<drape::Box, S>(brick, Eigen::Vector3d::Zero())}};
  const drape::SettleFields<S, decltype(solids)> fields{solids, t};
  const V y0(S(0.0015), S(0), S(0.0046));
  const V edge(S(0), S(0), S(1.8) * t);
  drape::SolidMotion<S> still{V::Zero(), V::Zero(), V::Zero(), S(0), S(0), -1};
  drape::ContactBuffer<S> buffer;
  buffer.resize(1);
  buffer.begin();
  const V up = V::UnitZ(), away = (y0 - edge).normalized();
  const S floorDepth = t - y0.z(), edgeDepth = t - (y0 - edge).norm();
  REQUIRE(floorDepth > 0);
  REQUIRE(edgeDepth > 0);
  buffer.template record<false>(0, y0 + floorDepth * up, up, floorDepth, still, y0, V::Zero());
  buffer.template record<false>(0, y0 + edgeDepth * away, away, edgeDepth, still, y0, V::Zero());
  REQUIRE(int(buffer.slotCount[0]) == 2);

  // The planes alone take their exact point, far along x and outside the box's surface grown by the slack.
  V planes = y0, binned = y0;
  drape::projectOntoContactPlanes(0, 1, buffer, &planes, &y0, &binned);
  CHECK(planes.x() - y0.x() > S(0.002));
  CHECK((planes - edge).norm() > t + S(drape::constants::kExactPointSlack) * (floorDepth + edgeDepth));
  // Judged by the fields, the floor backs its plane and the box does not back the tangent: the vertex takes the
  // least-squares compromise cut at 1/kRefusedReach^2, where the floor's and the edge's pushes nearly cancel.
  V judged = y0;
  drape::projectOntoContactPlanes(0, 1, buffer, &judged, &y0, &binned, fields);
  CHECK(std::abs(judged.x() - y0.x()) < S(0.0005));
  const V n[2] = {buffer.slots[0][0].normal, buffer.slots[0][1].normal};
  const S b[2] = {buffer.slots[0][0].offset, buffer.slots[0][1].offset};
  CHECK((judged - drape::leastSquaresCompromise(n, b, 2, y0, drape::constants::kRefusedReach)).norm() == S(0));
  // A flat wall along the tangent (a plane through the edge, facing as the tangent does) backs it everywhere: with
  // the floor, every plane at the point is a surface there, and the point is taken.
  drape::Solid<drape::Plane> wall;
  wall.pose.rotation = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), away.template cast<double>());
  wall.pose.position = edge.template cast<double>();
  const std::tuple<std::vector<CompiledSolid<drape::Plane, S>>> walls{
      {drape::detail::compileSolid<drape::Plane, S>(drape::Solid<drape::Plane>{}, Eigen::Vector3d::Zero()),
       drape::detail::compileSolid<drape::Plane, S>(wall, Eigen::Vector3d::Zero())}};
  V taken = y0;
  const drape::SettleFields<S, decltype(walls)> wallFields{walls, t};
  drape::projectOntoContactPlanes(0, 1, buffer, &taken, &y0, &binned, wallFields);
  CHECK((taken - planes).norm() <= S(1e-5) * t);
}

TEMPLATE_TEST_CASE("a cloth drawn frictionless from under the heavy brick is not stretched by jumps past its edge",
                   "[contacts][pinch]", float, double) {
  // The heavy brick's scene (scenes/heavy_brick.hpp, 1.8 thicknesses) without friction: nothing resists the pull
  // but the pinch, so a stretched edge is a vertex thrown along the pull. With every exact point of the settle
  // taken, a vertex leaving the gap jumped to where the floor's plane meets the brick edge's tangent, 2-4 mm
  // along, and the edge behind it reached a strain of 0.207 (float) and 0.201 (double); with the fields judging
  // the point, 0.068 and 0.069 (docs/design.md §16, "Exact points tested").
  using S = TestType;
  drape::scenes::BrickConfig c;
  c.friction = 0;
  const drape::scenes::BrickResult r = drape::scenes::runHeavyBrick<S>(c);
  INFO("strain " << r.maxStrain << ", fastest vertex " << r.maxSpeed << " m/s");
  CHECK(r.finite);
  CHECK(r.underAtEnd == 0);
  CHECK(r.maxFloorPenetration == 0);
  CHECK(r.maxBrickPenetration == 0);
  CHECK(r.maxStrain < 0.1);
}

TEMPLATE_TEST_CASE("a solid pressed edge first onto a cloth on the floor does not drag it into the floor by friction",
                   "[contacts][friction]", float, double) {
  // A long box turned 30 or 45 degrees about its length comes down edge first at 1 m/s onto a cloth lying on a
  // floor (friction 0.3 on the box, 0.5 on the floor) and stops with its edge 2 mm or 8 mm above the floor. The
  // cloth beside the edge touches the box's sloping sides; their position friction carries it along the box's
  // motion in their tangent planes, which slope into the floor, and the box's pushes beside the edge press it into
  // the floor. Before the response kept its vertices out of the planes (holdOutOfPlane), vertices ended substeps
  // 2.1-12.5 mm below the floor's surface; none may (docs/design.md §4).
  using S = TestType;
  const double thickness = drape::Settings{}.thickness;
  for (const double tilt : {30.0, 45.0})
    for (const double gap : {0.002, 0.008}) {
      drape::Solver<S> cloth(std::make_shared<const drape::ClothAsset<S>>(
          drape::ClothAsset<S>::sheet(drape::scenes::edgePressSheet(thickness))));
      double lowest = thickness;
      drape::scenes::pressEdgeFirst(cloth, tilt * std::numbers::pi / 180, gap, [&](drape::Solver<S>& c, double dt) {
        c.step(dt, [&](const drape::Solver<S>& s) {
          for (drape::Index i = 0; i < s.vertexCount(); ++i) lowest = std::min(lowest, s.position(i).z());
        });
      });
      INFO("tilt " << tilt << " degrees, the edge stopping " << gap * 1e3 << " mm above the floor: lowest vertex "
                   << lowest * 1e3 << " mm");
      CHECK(lowest >= -1e-4 * thickness);  // a vertex within kSettleSlack of where the hold puts it stays
    }
}
