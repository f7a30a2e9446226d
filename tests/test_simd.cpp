// The SIMD constraint kernels (four lanes in SSE2, eight in AVX2) against the scalar kernel, bit for bit, and
// the solver's per-lane copies of the inverse masses against changes of a mass.
#include <drape/drape.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstring>
#include <memory>
#include <random>
#include <type_traits>
#include <vector>

namespace {

using drape::Index;
using drape::SimdLevel;

/// An irregular cloth: a 13 x 11 grid (odd sizes, so colours end in partial blocks and odd block counts) with
/// its positions jittered by up to 30 % of the spacing, as a mesh (every edge a stretch constraint) or a grid.
std::shared_ptr<const drape::ClothAsset<float>> jitteredCloth(bool mesh) {
  drape::SheetDesc g;
  g.nx = 13;
  g.ny = 11;
  g.spacing = 0.02;
  const auto grid = drape::ClothAsset<float>::sheet(g);
  if (!mesh) return std::make_shared<const drape::ClothAsset<float>>(grid);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-0.006f, 0.006f);
  std::vector<drape::Vec3<float>> x = grid.restPositions;
  for (auto& p : x) p += drape::Vec3<float>(u(rng), u(rng), u(rng));
  return std::make_shared<const drape::ClothAsset<float>>(drape::ClothAsset<float>::fromMesh(x, grid.triangles));
}

/// The positions of the test: the rest shape scaled by 1.05 and jittered, with vertex 0 put on vertex 1 (a
/// constraint of zero length, which has no direction and must be left alone by every kernel).
std::vector<drape::Vec4<float>> deformed(const drape::ClothAsset<float>& asset, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-0.004f, 0.004f);
  std::vector<drape::Vec4<float>> x(asset.vertexCount());
  for (Index i = 0; i < asset.vertexCount(); ++i) {
    const drape::Vec3<float> p = 1.05f * asset.restPositions[i] + drape::Vec3<float>(u(rng), u(rng), u(rng));
    x[i] = drape::Vec4<float>(p.x(), p.y(), p.z(), 0.0f);
  }
  x[0] = x[1];
  return x;
}

/// Inverse masses in [0.5, 20] with every seventh vertex pinned (0), so some constraints have one fixed end
/// and some (with compliance 0) two.
std::vector<float> masses(Index n) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.5f, 20.0f);
  std::vector<float> w(n);
  for (Index i = 0; i < n; ++i) w[i] = i % 7 == 3 ? 0.0f : u(rng);
  return w;
}

template <class V> bool sameBits(const std::vector<V>& a, const std::vector<V>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(V)) == 0;
}

#if defined(__FMA__)
// Built for a processor with FMA (e.g. -march=native): the compiler may fuse a * b + c in the scalar and SSE
// kernels, never in the AVX2 one, so the kernels agree to rounding rather than bit for bit.
constexpr bool kFusedBuild = true;
#else
constexpr bool kFusedBuild = false;
#endif

/// The kernels' positions (or velocities) agree: bit for bit, or in a fused build within 1e-6 (a few float ulps
/// at 0.2 m).
template <class V> bool agree(const std::vector<V>& a, const std::vector<V>& b) {
  if (!kFusedBuild) return sameBits(a, b);
  for (std::size_t i = 0; i < a.size(); ++i)
    if ((a[i] - b[i]).cwiseAbs().maxCoeff() > 1e-6f) return false;
  return true;
}

/// The scalar kernel keeps a multiplier per constraint, the SIMD kernels per lane: lane of constraint k.
Index laneOf(const drape::DistanceSet<float>& set, const drape::DistanceBlocks<float>& blocks, Index k) {
  Index c = 0;
  while (set.colourOffsets[c + 1] <= k) ++c;
  return blocks.blockOffsets[c] * drape::DistanceBlock<float>::kLanes + (k - set.colourOffsets[c]);
}

}  // namespace

TEST_CASE("the SIMD constraint kernels give the scalar kernel's bits", "[simd]") {
  const SimdLevel best = drape::bestSimdLevel();
  if (best < SimdLevel::Avx2) WARN("this processor lacks AVX2: the eight-lane kernel is not compared");
  if (best < SimdLevel::Sse2) WARN("this build has no SSE2: only the scalar kernel runs");
  if (kFusedBuild) WARN("a build with FMA: the kernels are compared to rounding, not bit for bit");
  for (const bool mesh : {false, true}) {
    const auto asset = jitteredCloth(mesh);
    const std::vector<float> w = masses(asset->vertexCount());
    for (const auto* set : {&asset->stretch, &asset->shear, &asset->bending}) {
      if (set->size() == 0) continue;
      drape::DistanceBlocks<float> lanes(*set);
      lanes.gatherMasses(w.data());
      for (const float alpha : {0.0f, 0.37f}) {
        for (const bool multipliers : {false, true}) {
          INFO("mesh " << mesh << ", set of " << set->size() << " constraints, alpha~ " << alpha
                       << ", multipliers " << multipliers);
          // Three passes from the same start, as three iterations of a substep.
          auto run = [&](SimdLevel level, std::vector<float>& lambda) {
            std::vector<drape::Vec4<float>> x = deformed(*asset, 5);
            lambda.assign(std::size_t(lanes.lambdaCount(*set)), 0.0f);
            for (int pass = 0; pass < 3; ++pass) {
              if (multipliers)
                drape::solveDistanceSet<true>(*set, lanes, alpha, lambda.data(), x.data(), w.data(), level);
              else
                drape::solveDistanceSet<false>(*set, lanes, alpha, static_cast<float*>(nullptr), x.data(), w.data(), level);
            }
            return x;
          };
          std::vector<float> lambdaScalar, lambdaSse, lambdaAvx;
          const auto scalar = run(SimdLevel::Scalar, lambdaScalar);
          // The kernels did something: the deformed start is not a solution.
          CHECK(!sameBits(scalar, deformed(*asset, 5)));
          // The zero-length constraint moved neither end along a direction it does not have: both ends moved
          // only through their other constraints, so they are finite.
          CHECK(scalar[0].allFinite());
          for (const SimdLevel level : {SimdLevel::Sse2, SimdLevel::Avx2}) {
            if (level > best) continue;
            std::vector<float>& lambda = level == SimdLevel::Sse2 ? lambdaSse : lambdaAvx;
            const auto simd = run(level, lambda);
            INFO("SIMD level " << int(level));
            CHECK(agree(simd, scalar));
            if (multipliers && !kFusedBuild) {
              int differing = 0;
              for (Index k = 0; k < set->size(); ++k)
                if (std::memcmp(&lambdaScalar[k], &lambda[laneOf(*set, lanes, k)], sizeof(float)) != 0) ++differing;
              CHECK(differing == 0);
            }
          }
        }
      }
    }
  }
}

TEMPLATE_TEST_CASE("a vertex pinned or freed between steps is solved with its new mass", "[simd][input]", float,
                   double) {
  drape::SheetDesc g;
  g.nx = 9;
  g.ny = 9;
  g.spacing = 0.05;
  auto asset = std::make_shared<const drape::ClothAsset<TestType>>(drape::ClothAsset<TestType>::sheet(g));
  drape::Settings settings;
  settings.subStepCount = 4;
  drape::Solver<TestType> solver(asset, settings);
  solver.pin(0);
  solver.pin(8);
  for (int f = 0; f < 20; ++f) solver.step(1.0 / 60.0);
  // Pinned while the cloth swings: the constraints must no longer move it (a stale copy of its old mass would).
  const drape::Index middle = 4 * 9 + 4;
  solver.pin(middle);
  const Eigen::Vector3d held = solver.position(middle);
  for (int f = 0; f < 20; ++f) {
    solver.step(1.0 / 60.0);
    REQUIRE(solver.position(middle) == held);
  }
  // Freed again, it falls with the cloth around it.
  solver.setInverseMass(middle, 1.0);
  for (int f = 0; f < 20; ++f) solver.step(1.0 / 60.0);
  CHECK(solver.position(middle).z() < held.z() - 0.01);
}

TEST_CASE("the four- and eight-lane contact responses give the scalar response's bits", "[simd][contacts]") {
  if (drape::bestSimdLevel() < SimdLevel::Avx2)
    WARN("this processor lacks AVX2: the eight-lane response is not compared");
  if (drape::bestSimdLevel() < SimdLevel::Sse2) WARN("this build has no SSE2: only the scalar response runs");
  if (kFusedBuild) WARN("a build with FMA: the responses are compared to rounding, not bit for bit");
  using V = drape::Vec3<float>;
  const Index n = 403;  // not a multiple of four: a partial four at the end
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), unit(0.0f, 1.0f);
  drape::ContactBuffer<float> contacts;
  contacts.resize(n);
  contacts.begin();
  std::vector<V> x0(n), xPrev(n), v0(n);
  int stuck = 0, sliding = 0, resting = 0;
  const float h = 1.0f / 300.0f;
  for (Index i = 0; i < n; ++i) {
    xPrev[i] = 0.01f * V(u(rng), u(rng), u(rng));  // near the origin, where a last bit of a move shows
    x0[i] = xPrev[i] + 2e-3f * V(u(rng), u(rng), u(rng));
    v0[i] = V(u(rng), u(rng), u(rng));
    if (i % 11 == 5) continue;  // not in contact: its four takes the scalar path
    const int slots = i % 13 == 7 ? 2 : 1;  // a second surface: the scalar path too
    contacts.stamp[i] = contacts.current;
    contacts.slotCount[i] = std::uint8_t(slots);
    for (int k = 0; k < slots; ++k) {
      drape::ContactSlot<float> c;
      c.normal = V(u(rng), u(rng), u(rng)).normalized();
      c.solidVelocity = i % 3 == 0 ? V::Zero() : V(0.2f * u(rng), 0.2f * u(rng), 0.2f * u(rng));
      c.correction = 2e-3f * unit(rng);
      c.staticFriction = i % 7 == 0 ? 0.0f : 2.0f * unit(rng);
      c.dynamicFriction = c.staticFriction * unit(rng);
      c.offset = c.normal.dot(x0[i]);
      c.body = -1;
      contacts.slots[i][k] = c;
    }
    const drape::ContactSlot<float>& c = contacts.slots[i][0];
    if (i % 17 == 0) v0[i] = c.solidVelocity;  // no speed relative to the solid: the speed's division is skipped
    if (i % 17 == 0) ++resting;
    if (slots == 1) {
      const V disp = (x0[i] - xPrev[i]) - h * c.solidVelocity;
      const bool stick = (disp - c.normal.dot(disp) * c.normal).norm() <= c.staticFriction * c.correction;
      (stick ? stuck : sliding)++;
    }
  }
  // The inputs reach both of friction's cases and a vertex at rest on its solid.
  CHECK(stuck > 20);
  CHECK(sliding > 20);
  CHECK(resting > 10);
  for (const bool friction : {false, true}) {
    auto run = [&](SimdLevel level, std::vector<V>& x, std::vector<V>& v, std::vector<float>& dv) {
      x = x0, v = v0;
      drape::ContactBuffer<float> c = contacts;
      for (Index begin = 0; begin < n; begin += 100) {  // shares of 100, as threads would take them
        const Index end = std::min(begin + 100, n);
        if (friction)
          drape::respondContacts<true>(begin, end, c, x.data(), xPrev.data(), v.data(), h, 0.3f, level);
        else
          drape::respondContacts<false>(begin, end, c, x.data(), xPrev.data(), v.data(), h, 0.3f, level);
      }
      dv = c.normalDv;
      for (Index i = 0; i < n; ++i)
        if (!c.live(i)) dv[i] = 0;  // not written for a vertex out of contact
    };
    std::vector<V> xs, vs;
    std::vector<float> dvs;
    run(SimdLevel::Scalar, xs, vs, dvs);
    INFO("friction " << friction);
    CHECK((xs != x0) == friction);  // friction moved positions, and only friction
    CHECK(vs != v0);
    for (const SimdLevel level : {SimdLevel::Sse2, SimdLevel::Avx2}) {
      if (level > drape::bestSimdLevel()) continue;
      INFO("SIMD level " << int(level));
      std::vector<V> xv, vv;
      std::vector<float> dvv;
      run(level, xv, vv, dvv);
      CHECK(agree(xs, xv));
      CHECK(agree(vs, vv));
      if (!kFusedBuild) CHECK(sameBits(dvs, dvv));
    }
  }
}

TEMPLATE_TEST_CASE("a plane's four-lane vertex test gives the scalar test's bits", "[simd][contacts]", float, double) {
  // The same vertices through the pass once as all items (a float plane's test takes aligned fours) and once
  // as a list of the same indices (always the scalar loop).
  using S = TestType;
  using V = drape::Vec3<S>;
  const Index n = 203;
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  drape::Solid<drape::Plane> plane;
  plane.pose.rotation = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), Eigen::Vector3d(0.3, -0.2, 1.0));
  plane.pose.position = Eigen::Vector3d(0.1, 0.2, 0.05);
  plane.motion = drape::Motion::Kinematic;  // a moving plane: its velocity at each contact is recorded
  plane.staticFriction = 0.4;
  plane.dynamicFriction = 0.3;
  plane.linearVelocity = Eigen::Vector3d(0.2, -0.1, 0.05);
  plane.angularVelocity = Eigen::Vector3d(0.5, 1.0, -2.0);
  const auto solid = drape::detail::compileSolid<drape::Plane, S>(plane, Eigen::Vector3d::Zero());
  const S thickness = S(0.005), slack = S(1e-4);
  std::vector<V> x0(n);
  std::vector<S> w(n);
  std::vector<Index> list(n);
  for (Index i = 0; i < n; ++i) {
    // Heights from 2 cm below to 2 cm above the plane: about half within the thickness.
    const V along(S(u(rng)), S(u(rng)), S(u(rng)));
    const S height = S(0.02 * u(rng));
    x0[i] = along - (solid.sdf.normal.dot(along) - solid.sdf.offset - height) * solid.sdf.normal;
    w[i] = i % 9 == 4 ? S(0) : S(1);  // every ninth pinned: never moved
    list[i] = i;
  }
  x0[7] -= (solid.sdf.normal.dot(x0[7]) - solid.sdf.offset - S(0.001)) * solid.sdf.normal;  // inside (see below)
  auto run = [&](bool all, std::vector<V>& x, drape::ContactBuffer<S>& contacts) {
    x = x0;
    contacts.resize(n);
    contacts.begin();
    // A vertex already in contact with another surface this substep: the plane's contact joins it.
    contacts.template record<false>(7, x[7], V(1, 0, 0), S(1e-3), solid.motion, x[7], V::Zero());
    drape::VertexPassShare<S> share;
    for (Index begin = 0; begin < n; begin += 50) {  // shares of 50, as threads might take them
      const Index end = std::min(begin + 50, n);
      const auto part = all ? drape::projectVertexContacts(begin, end, solid, thickness, x.data(), w.data(),
                                                           drape::AllItems{}, contacts, x0.data(), slack)
                            : drape::projectVertexContacts(begin, end, solid, thickness, x.data(), w.data(),
                                                           drape::ItemList{list.data()}, contacts, x0.data(), slack);
      share.found += part.found;
      share.moved = std::max(share.moved, part.moved);
    }
    return share;
  };
  std::vector<V> xa, xl;
  drape::ContactBuffer<S> ca, cl;
  const auto sa = run(true, xa, ca), sl = run(false, xl, cl);
  CHECK(sa.found > n / 4);
  CHECK(sa.found < n - n / 4);
  CHECK(sa.found == sl.found);
  // A build with FMA may fuse the lanes' and the scalar loop's multiply-adds differently: rounding, not bits.
  const bool bits = !(kFusedBuild && std::is_same_v<S, float>);
  if (bits) CHECK(std::memcmp(&sa.moved, &sl.moved, sizeof(S)) == 0);
  S worst = 0;
  for (Index i = 0; i < n; ++i) worst = std::max(worst, (xa[i] - xl[i]).cwiseAbs().maxCoeff());
  CHECK(worst <= (bits ? S(0) : S(1e-6)));
  int differing = 0;
  for (Index i = 0; i < n; ++i) {
    if (ca.live(i) != cl.live(i) || ca.slotCount[i] != cl.slotCount[i]) {
      ++differing;
      continue;
    }
    for (int k = 0; k < ca.slotCount[i]; ++k)
      if (bits ? std::memcmp(&ca.slots[i][k], &cl.slots[i][k], sizeof(drape::ContactSlot<S>)) != 0
               : (ca.slots[i][k].correction - cl.slots[i][k].correction) > S(1e-6) ||
                     (cl.slots[i][k].correction - ca.slots[i][k].correction) > S(1e-6))
        ++differing;
  }
  CHECK(differing == 0);
  CHECK(cl.slotCount[7] == 2);  // the earlier surface kept its slot
}

TEST_CASE("the four-lane prediction and velocity update give the scalar loops' bits", "[simd]") {
  if (drape::bestSimdLevel() < SimdLevel::Sse2) WARN("this build has no SSE2: only the scalar loops run");
  if (kFusedBuild) WARN("a build with FMA: the loops are compared to rounding, not bit for bit");
  using V = drape::Vec3<float>;
  using P = drape::Vec4<float>;
  const Index n = 203;  // a partial four at the end
  std::mt19937 rng(29);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<V> x(n), v0(n), reference(n);
  std::vector<float> w(n);
  std::vector<P> solved(n);
  for (Index i = 0; i < n; ++i) {
    x[i] = 0.01f * V(u(rng), u(rng), u(rng));  // near the origin, where a last bit of a move shows
    v0[i] = V(u(rng), u(rng), u(rng));
    w[i] = i % 9 == 4 ? 0.0f : 1.0f + u(rng);  // every ninth pinned: not moved, its velocity set to zero
    solved[i] = P(x[i].x() + 1e-3f * u(rng), x[i].y() + 1e-3f * u(rng), x[i].z() + 1e-3f * u(rng), 0.0f);
  }
  const V gh(0.3f, -0.2f, -9.81f / 300.0f);
  const float h = 1.0f / 300.0f, keep = 0.997f;
  auto predict = [&](SimdLevel level, bool keepStart, bool damp, std::vector<V>& v, std::vector<V>& x0,
                     std::vector<V>& xp, std::vector<P>& xw) {
    v = v0, x0.assign(n, V::Zero()), xp.assign(n, V::Zero()), xw.assign(n, P::Constant(7.0f));
    for (Index begin = 0; begin < n; begin += 50) {  // shares of 50: starts that are not a multiple of four
      const Index end = std::min(begin + 50, n);
      if (keepStart && damp)
        drape::predictPositions<true, true>(begin, end, x.data(), v.data(), w.data(), gh, h, x0.data(), xp.data(),
                                            xw.data(), keep, level);
      else if (keepStart)
        drape::predictPositions<true, false>(begin, end, x.data(), v.data(), w.data(), gh, h, x0.data(), xp.data(),
                                             xw.data(), keep, level);
      else if (damp)
        drape::predictPositions<false, true>(begin, end, x.data(), v.data(), w.data(), gh, h, x0.data(), xp.data(),
                                             xw.data(), keep, level);
      else
        drape::predictPositions<false, false>(begin, end, x.data(), v.data(), w.data(), gh, h, x0.data(),
                                              xp.data(), xw.data(), keep, level);
    }
  };
  for (const bool keepStart : {false, true})
    for (const bool damp : {false, true}) {
      INFO("keep the start " << keepStart << ", damp " << damp);
      std::vector<V> vs, x0s, xps, vl, x0l, xpl;
      std::vector<P> xws, xwl;
      predict(SimdLevel::Scalar, keepStart, damp, vs, x0s, xps, xws);
      CHECK(vs[4] == V::Zero());  // pinned (the update then gives it its pin's move)
      CHECK(xps[4] == x[4]);
      CHECK(vs[5] != v0[5]);
      CHECK((x0s == x) == keepStart);
      CHECK(xws[n - 1].w() == 0.0f);
      predict(SimdLevel::Sse2, keepStart, damp, vl, x0l, xpl, xwl);
      CHECK(agree(vs, vl));
      CHECK(agree(x0s, x0l));
      CHECK(agree(xps, xpl));
      CHECK(agree(xws, xwl));
    }
  for (const bool keepSolved : {false, true}) {
    INFO("keep the solved positions " << keepSolved);
    auto update = [&](SimdLevel level, std::vector<V>& xo, std::vector<V>& v, std::vector<V>& xp) {
      xo.assign(n, V::Zero()), v = v0, xp = x;
      for (Index begin = 0; begin < n; begin += 50) {
        const Index end = std::min(begin + 50, n);
        if (keepSolved)
          drape::updateVelocities<true, false>(begin, end, solved.data(), xp.data(), xo.data(), v.data(), 1.0f / h,
                                               static_cast<const V*>(nullptr), level);
        else
          drape::updateVelocities<false, false>(begin, end, solved.data(), xp.data(), xo.data(), v.data(),
                                                1.0f / h, static_cast<const V*>(nullptr), level);
      }
    };
    std::vector<V> xs, vs, xps, xl, vl, xpl;
    update(SimdLevel::Scalar, xs, vs, xps);
    CHECK(xs[n - 1] == solved[n - 1].head<3>());
    CHECK((xps == xs) == keepSolved);
    update(SimdLevel::Sse2, xl, vl, xpl);
    CHECK(agree(xs, xl));
    CHECK(agree(vs, vl));
    CHECK(agree(xps, xpl));
  }
}

TEST_CASE("the spin sums in AVX2 lanes give the scalar loop's bits and the sums they stand for", "[simd][spin]") {
  if (drape::bestSimdLevel() < SimdLevel::Avx2) WARN("this processor lacks AVX2: only the scalar loop runs");
  if (kFusedBuild) WARN("a build with FMA: the kernels are compared to rounding, not bit for bit");
  using V = drape::Vec3<float>;
  using P = drape::Vec4<float>;
  const Index n = 203;  // a partial four at the end
  std::mt19937 rng(31);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<V> start(n), predicted(n);
  std::vector<P> solved(n);
  std::vector<float> w(n);
  for (Index i = 0; i < n; ++i) {
    start[i] = 0.5f * V(u(rng), u(rng), u(rng));
    predicted[i] = start[i] + 1e-3f * V(u(rng), u(rng), u(rng));
    const V x = predicted[i] + 1e-4f * V(u(rng), u(rng), u(rng));
    solved[i] = P(x.x(), x.y(), x.z(), 0.0f);
    w[i] = i % 7 == 3 ? 0.0f : 500.0f * (1.5f + u(rng));  // every seventh kinematic: no mass in any sum
  }
  for (Index begin = 0; begin < n; begin += 50) {  // shares of 50: starts that are not a multiple of four
    const Index end = std::min(begin + 50, n);
    INFO("vertices " << begin << " to " << end);
    const drape::SpinSums scalar =
        drape::sumSolvePushes(begin, end, solved.data(), predicted.data(), start.data(), w.data(), SimdLevel::Scalar);
    // The definitions, in long double, vertex by vertex.
    long double moment[3] = {}, push[3] = {}, weight = 0, first[3] = {}, second[3][3] = {};
    for (Index i = begin; i < end; ++i) {
      if (!(w[i] > 0.0f)) continue;
      const long double m = 1.0L / w[i];
      long double x[3], d[3], s[3];
      for (int k = 0; k < 3; ++k) x[k] = solved[i][k], d[k] = m * (x[k] - predicted[i][k]), s[k] = start[i][k];
      moment[0] += s[1] * d[2] - s[2] * d[1], moment[1] += s[2] * d[0] - s[0] * d[2];
      moment[2] += s[0] * d[1] - s[1] * d[0];
      weight += m;
      for (int k = 0; k < 3; ++k) {
        push[k] += d[k], first[k] += m * x[k];
        for (int l = 0; l < 3; ++l) second[k][l] += m * x[k] * x[l];
      }
    }
    const auto near = [](double got, long double want, long double scale) {
      return std::abs(static_cast<long double>(got) - want) <= 1e-13L * scale;
    };
    for (int k = 0; k < 3; ++k) {
      CHECK(near(scalar.moment[k], moment[k], 0.5L * 1e-4L * weight));
      CHECK(near(scalar.push[k], push[k], 1e-4L * weight));
      CHECK(near(scalar.first[k], first[k], weight));
      for (int l = 0; l < 3; ++l) CHECK(near(scalar.second(k, l), second[k][l], weight));
    }
    CHECK(near(scalar.weight, weight, weight));
    if (drape::bestSimdLevel() < SimdLevel::Avx2) continue;
    const drape::SpinSums lanes =
        drape::sumSolvePushes(begin, end, solved.data(), predicted.data(), start.data(), w.data(), SimdLevel::Avx2);
    const auto same = [](const auto& a, const auto& b) {
      return kFusedBuild ? (a - b).cwiseAbs().maxCoeff() <= 1e-12 * (1 + b.cwiseAbs().maxCoeff()) : a == b;
    };
    CHECK(same(lanes.moment, scalar.moment));
    CHECK(same(lanes.push, scalar.push));
    CHECK(same(lanes.first, scalar.first));
    CHECK(same(lanes.second, scalar.second));
    CHECK((kFusedBuild ? std::abs(lanes.weight - scalar.weight) <= 1e-12 * scalar.weight
                       : lanes.weight == scalar.weight));
  }
  // The restoring rotation: four lanes against the scalar loop; kinematic vertices keep their velocity.
  if (drape::bestSimdLevel() < SimdLevel::Sse2) return;
  const Eigen::Vector3d omega(0.3, -1.7, 2.9), centre(0.1, -0.2, 0.05);
  std::vector<V> v0(n);
  for (auto& vi : v0) vi = V(u(rng), u(rng), u(rng));
  std::vector<V> vs = v0, vl = v0;
  for (Index begin = 0; begin < n; begin += 50) {
    const Index end = std::min(begin + 50, n);
    drape::applySpin(begin, end, solved.data(), w.data(), vs.data(), omega, centre, SimdLevel::Scalar);
    drape::applySpin(begin, end, solved.data(), w.data(), vl.data(), omega, centre, SimdLevel::Sse2);
  }
  CHECK(agree(vs, vl));
  CHECK(vs[3] == v0[3]);  // kinematic
  CHECK(vs[4] != v0[4]);
}
