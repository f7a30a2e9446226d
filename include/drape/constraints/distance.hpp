#pragma once
// XPBD distance constraints C = |x_a - x_b| - l0, solved Gauss-Seidel colour by colour. Stretch, shear and
// bending all use this kernel: bending is a distance between the far vertices of two adjacent faces, which
// stays stable at compliance 0 (a dihedral-angle bend does not at 2 cm spacing).
//
// The solve works on packed positions, (x, y, z, 0) in one Vec4, so a vertex is one aligned load and store.
// Float solves the constraints of a colour four at a time in SSE registers (DistanceBlock), or eight at a time
// in AVX2 registers where the processor has them, lane by lane with exactly the scalar kernel's operations in
// the same order, so all three give the same bits; the inverse masses of a block's ends come from its lane copies,
// two loads. Double runs the scalar kernel over the same layout. (A build for a processor with FMA, such as
// -march=native, lets the compiler fuse a * b + c in the scalar and SSE kernels; they then round a little
// differently from the AVX2 kernel, which never fuses. Each kernel is still deterministic.)

#include <drape/cloth/asset.hpp>
#include <drape/cloth/spin.hpp>

#include <drape/detail/simd.hpp>

namespace drape {

/// Four constraints of one colour side by side, the unit the solver's SIMD kernel works on (one SSE register
/// of floats). Each end is kept as 4 x its vertex index, the offset of the vertex among the packed positions'
/// scalars (four per vertex), which an x86 load addresses in the same instruction as the base.
template <Scalar S> struct DistanceBlock {
  static constexpr int kLanes = 4;
  Index a[kLanes], b[kLanes];  ///< 4 x the vertex indices of each pair
  S rest[kLanes];              ///< rest lengths (m)

  Index vertexA(int lane) const { return a[lane] / 4; }
  Index vertexB(int lane) const { return b[lane] / 4; }
};

/// A set's constraints as the float SIMD kernels read them, built by the solver from the asset's DistanceSet:
/// colour c in blocks [blockOffsets[c], blockOffsets[c+1]). The lanes past a colour's last constraint repeat
/// the first constraint of their block: a repeated lane reads what its original reads and writes what it
/// writes, so a block is solved whole, without a mask. massA and massB copy the inverse masses at both ends of
/// every lane (lane k of block j at 4 j + k), so the kernel reads them with two loads; whoever changes a mass
/// gathers them again.
template <Scalar S> struct DistanceBlocks {
  std::vector<DistanceBlock<S>> blocks;
  std::vector<Index> blockOffsets{0};
  std::vector<S> massA, massB;

  explicit DistanceBlocks(const DistanceSet<S>& set) {
    const Index colours = set.colourCount();
    constexpr Index kLanes = DistanceBlock<S>::kLanes;
    blockOffsets.assign(colours + 1, 0);
    for (Index c = 0; c < colours; ++c) {
      const Index begin = set.colourOffsets[c], end = set.colourOffsets[c + 1];
      blockOffsets[c + 1] = blockOffsets[c] + (end - begin + kLanes - 1) / kLanes;
      for (Index first = begin; first < end; first += kLanes) {
        DistanceBlock<S> block;
        for (Index lane = 0; lane < kLanes; ++lane) {
          const Index k = first + lane < end ? first + lane : first;
          block.a[lane] = 4 * set.pairs[k][0];
          block.b[lane] = 4 * set.pairs[k][1];
          block.rest[lane] = set.restLength[k];
        }
        blocks.push_back(block);
      }
    }
  }
  DistanceBlocks() = default;

  void gatherMasses(const S* invMass) {
    constexpr int kLanes = DistanceBlock<S>::kLanes;
    massA.resize(blocks.size() * kLanes);
    massB.resize(blocks.size() * kLanes);
    for (std::size_t j = 0; j < blocks.size(); ++j)
      for (int k = 0; k < kLanes; ++k) {
        massA[j * kLanes + k] = invMass[blocks[j].vertexA(k)];
        massB[j * kLanes + k] = invMass[blocks[j].vertexB(k)];
      }
  }
  /// Multipliers a solver keeps for `set`: one per constraint, or per lane where that is more.
  Index lambdaCount(const DistanceSet<S>& set) const {
    return std::max(set.size(), Index(blocks.size()) * DistanceBlock<S>::kLanes);
  }
};

namespace detail {

/// One constraint on packed vertices (written per component: Eigen's vector expressions cost more
/// instructions here). lambda may be null when kLambda is false.
template <bool kLambda, Scalar S>
inline void solveDistance(Index a, Index b, S rest, S alphaTilde, S* lambda, Vec4<S>* xw, const S* invMass) {
  const S wa = invMass[a], wb = invMass[b];
  S* pa = xw[a].data();
  S* pb = xw[b].data();
  // Every coordinate is read before any is written: a and b differ, but the compiler cannot know it and would
  // reload b after storing a.
  const S ax = pa[0], ay = pa[1], az = pa[2], bx = pb[0], by = pb[1], bz = pb[2];
  const S dx = ax - bx, dy = ay - by, dz = az - bz;
  const S len = std::sqrt(dx * dx + dy * dy + dz * dz);
  const S denom = wa + wb + alphaTilde;
  if (!(denom > S(0) && len > S(0))) return;  // both fixed and rigid, or coincident: no direction
  S s;                                         // the correction along d per unit inverse mass
  if constexpr (kLambda) {
    const S dLambda = (rest - len - alphaTilde * *lambda) / denom;
    *lambda += dLambda;
    s = dLambda / len;
  } else {
    s = (rest - len) / (denom * len);
  }
  const S sa = wa * s, sb = wb * s;
  pa[0] = ax + sa * dx, pa[1] = ay + sa * dy, pa[2] = az + sa * dz;
  pb[0] = bx - sb * dx, pb[1] = by - sb * dy, pb[2] = bz - sb * dz;
}

#if DRAPE_SSE2
/// Lane k of v in every lane.
template <int k> inline __m128 broadcast(__m128 v) { return _mm_shuffle_ps(v, v, _MM_SHUFFLE(k, k, k, k)); }

/// A block of four float constraints of one colour, lane by lane the scalar kernel's arithmetic in the same
/// order. The differences d = a - b stay as loaded, one vertex per register (their fourth coordinate is 0);
/// only their squares are transposed, to sum each one's three, and each constraint's correction factor is
/// broadcast back onto its own d. A lane whose constraint has no direction (zero length) or cannot move (both
/// ends fixed and rigid) divides by 1 instead and is masked to no correction, so no lane raises a
/// floating-point exception that the scalar kernel would not.
template <bool kLambda>
inline void solveDistanceBlock(const DistanceBlock<float>& block, const float* massA, const float* massB,
                               __m128 alphaTilde, float* lambda, Vec4<float>* xw) {
  float* const base = xw->data();
  float* const pa0 = base + block.a[0];
  float* const pa1 = base + block.a[1];
  float* const pa2 = base + block.a[2];
  float* const pa3 = base + block.a[3];
  float* const pb0 = base + block.b[0];
  float* const pb1 = base + block.b[1];
  float* const pb2 = base + block.b[2];
  float* const pb3 = base + block.b[3];
  const __m128 a0 = _mm_load_ps(pa0), a1 = _mm_load_ps(pa1), a2 = _mm_load_ps(pa2), a3 = _mm_load_ps(pa3);
  const __m128 b0 = _mm_load_ps(pb0), b1 = _mm_load_ps(pb1), b2 = _mm_load_ps(pb2), b3 = _mm_load_ps(pb3);
  const __m128 d0 = _mm_sub_ps(a0, b0), d1 = _mm_sub_ps(a1, b1), d2 = _mm_sub_ps(a2, b2), d3 = _mm_sub_ps(a3, b3);
  __m128 qx = _mm_mul_ps(d0, d0), qy = _mm_mul_ps(d1, d1), qz = _mm_mul_ps(d2, d2), qw = _mm_mul_ps(d3, d3);
  _MM_TRANSPOSE4_PS(qx, qy, qz, qw);  // now qx holds the four dx^2, qy the dy^2, qz the dz^2 (qw zeros)
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
  const __m128 len = _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(qx, qy), qz));
  const __m128 wa = _mm_loadu_ps(massA), wb = _mm_loadu_ps(massB);
  const __m128 denom = _mm_add_ps(_mm_add_ps(wa, wb), alphaTilde);
  const __m128 live = _mm_and_ps(_mm_cmpgt_ps(denom, zero), _mm_cmpgt_ps(len, zero));
  const __m128 safeLen = select(live, len, one), safeDenom = select(live, denom, one);
  const __m128 rest = _mm_loadu_ps(block.rest);
  __m128 s;
  if constexpr (kLambda) {
    const __m128 lam = _mm_loadu_ps(lambda);
    const __m128 dLambda =
        _mm_and_ps(live, _mm_div_ps(_mm_sub_ps(_mm_sub_ps(rest, len), _mm_mul_ps(alphaTilde, lam)), safeDenom));
    _mm_storeu_ps(lambda, _mm_add_ps(lam, dLambda));
    s = _mm_div_ps(dLambda, safeLen);
  } else {
    s = _mm_and_ps(live, _mm_div_ps(_mm_sub_ps(rest, len), _mm_mul_ps(safeDenom, safeLen)));
  }
  const __m128 sa = _mm_mul_ps(wa, s), sb = _mm_mul_ps(wb, s);
  // All of a's lanes before b's: a repeated lane stores what its original stored, and no b is an a.
  _mm_store_ps(pa0, _mm_add_ps(a0, _mm_mul_ps(broadcast<0>(sa), d0)));
  _mm_store_ps(pa1, _mm_add_ps(a1, _mm_mul_ps(broadcast<1>(sa), d1)));
  _mm_store_ps(pa2, _mm_add_ps(a2, _mm_mul_ps(broadcast<2>(sa), d2)));
  _mm_store_ps(pa3, _mm_add_ps(a3, _mm_mul_ps(broadcast<3>(sa), d3)));
  _mm_store_ps(pb0, _mm_sub_ps(b0, _mm_mul_ps(broadcast<0>(sb), d0)));
  _mm_store_ps(pb1, _mm_sub_ps(b1, _mm_mul_ps(broadcast<1>(sb), d1)));
  _mm_store_ps(pb2, _mm_sub_ps(b2, _mm_mul_ps(broadcast<2>(sb), d2)));
  _mm_store_ps(pb3, _mm_sub_ps(b3, _mm_mul_ps(broadcast<3>(sb), d3)));
}
#endif

#if DRAPE_AVX2

/// Two vertices in one register: lo's in the low half, hi's in the high half.
DRAPE_TARGET_AVX2 inline __m256 loadPair(const float* lo, const float* hi) {
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(lo)), _mm_load_ps(hi), 1);
}
DRAPE_TARGET_AVX2 inline void storePair(float* lo, float* hi, __m256 v) {
  _mm_store_ps(lo, _mm256_castps256_ps128(v));
  _mm_store_ps(hi, _mm256_extractf128_ps(v, 1));
}

/// Two blocks of one colour at once, lane by lane the SSE kernel's arithmetic (so the scalar kernel's). A
/// 256-bit register holds two vertices, one per 128-bit half: the first block's lane k and the second's lane k,
/// so that the in-half transposes and broadcasts of AVX leave the eight constraints in block order.
template <bool kLambda>
DRAPE_TARGET_AVX2 inline void solveDistanceBlockPair(const DistanceBlock<float>* block,
                                                                    const float* massA, const float* massB,
                                                                    float alphaTilde, float* lambda, Vec4<float>* xw) {
  float* const base = xw->data();
  const DistanceBlock<float>& p = block[0];
  const DistanceBlock<float>& q = block[1];
  const __m256 a0 = loadPair(base + p.a[0], base + q.a[0]), a1 = loadPair(base + p.a[1], base + q.a[1]);
  const __m256 a2 = loadPair(base + p.a[2], base + q.a[2]), a3 = loadPair(base + p.a[3], base + q.a[3]);
  const __m256 b0 = loadPair(base + p.b[0], base + q.b[0]), b1 = loadPair(base + p.b[1], base + q.b[1]);
  const __m256 b2 = loadPair(base + p.b[2], base + q.b[2]), b3 = loadPair(base + p.b[3], base + q.b[3]);
  const __m256 d0 = _mm256_sub_ps(a0, b0), d1 = _mm256_sub_ps(a1, b1);
  const __m256 d2 = _mm256_sub_ps(a2, b2), d3 = _mm256_sub_ps(a3, b3);
  const __m256 q0 = _mm256_mul_ps(d0, d0), q1 = _mm256_mul_ps(d1, d1);
  const __m256 q2 = _mm256_mul_ps(d2, d2), q3 = _mm256_mul_ps(d3, d3);
  // The 4 x 4 transpose in each half: t01 = (x0 x1 y0 y1), t23 = (x2 x3 y2 y3), u01 = (z0 z1 w0 w1), ...
  const __m256 t01 = _mm256_unpacklo_ps(q0, q1), t23 = _mm256_unpacklo_ps(q2, q3);
  const __m256 u01 = _mm256_unpackhi_ps(q0, q1), u23 = _mm256_unpackhi_ps(q2, q3);
  const __m256 qx = _mm256_castpd_ps(_mm256_unpacklo_pd(_mm256_castps_pd(t01), _mm256_castps_pd(t23)));
  const __m256 qy = _mm256_castpd_ps(_mm256_unpackhi_pd(_mm256_castps_pd(t01), _mm256_castps_pd(t23)));
  const __m256 qz = _mm256_castpd_ps(_mm256_unpacklo_pd(_mm256_castps_pd(u01), _mm256_castps_pd(u23)));
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), alpha = _mm256_set1_ps(alphaTilde);
  const __m256 len = _mm256_sqrt_ps(_mm256_add_ps(_mm256_add_ps(qx, qy), qz));
  // Lanes in block order: (p0 p1 p2 p3 | q0 q1 q2 q3), as the per-lane arrays hold them.
  const __m256 wa = _mm256_loadu_ps(massA), wb = _mm256_loadu_ps(massB);
  const __m256 denom = _mm256_add_ps(_mm256_add_ps(wa, wb), alpha);
  const __m256 live =
      _mm256_and_ps(_mm256_cmp_ps(denom, zero, _CMP_GT_OQ), _mm256_cmp_ps(len, zero, _CMP_GT_OQ));
  const __m256 safeLen = _mm256_blendv_ps(one, len, live), safeDenom = _mm256_blendv_ps(one, denom, live);
  const __m256 rest = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p.rest)), _mm_loadu_ps(q.rest), 1);
  __m256 s;
  if constexpr (kLambda) {
    const __m256 lam = _mm256_loadu_ps(lambda);
    const __m256 dLambda = _mm256_and_ps(
        live, _mm256_div_ps(_mm256_sub_ps(_mm256_sub_ps(rest, len), _mm256_mul_ps(alpha, lam)), safeDenom));
    _mm256_storeu_ps(lambda, _mm256_add_ps(lam, dLambda));
    s = _mm256_div_ps(dLambda, safeLen);
  } else {
    s = _mm256_and_ps(live, _mm256_div_ps(_mm256_sub_ps(rest, len), _mm256_mul_ps(safeDenom, safeLen)));
  }
  const __m256 sa = _mm256_mul_ps(wa, s), sb = _mm256_mul_ps(wb, s);
  // Lane k of each block: the in-half broadcast of lane k gives p's factor below and q's above.
  storePair(base + p.a[0], base + q.a[0], _mm256_add_ps(a0, _mm256_mul_ps(_mm256_shuffle_ps(sa, sa, 0x00), d0)));
  storePair(base + p.a[1], base + q.a[1], _mm256_add_ps(a1, _mm256_mul_ps(_mm256_shuffle_ps(sa, sa, 0x55), d1)));
  storePair(base + p.a[2], base + q.a[2], _mm256_add_ps(a2, _mm256_mul_ps(_mm256_shuffle_ps(sa, sa, 0xaa), d2)));
  storePair(base + p.a[3], base + q.a[3], _mm256_add_ps(a3, _mm256_mul_ps(_mm256_shuffle_ps(sa, sa, 0xff), d3)));
  storePair(base + p.b[0], base + q.b[0], _mm256_sub_ps(b0, _mm256_mul_ps(_mm256_shuffle_ps(sb, sb, 0x00), d0)));
  storePair(base + p.b[1], base + q.b[1], _mm256_sub_ps(b1, _mm256_mul_ps(_mm256_shuffle_ps(sb, sb, 0x55), d1)));
  storePair(base + p.b[2], base + q.b[2], _mm256_sub_ps(b2, _mm256_mul_ps(_mm256_shuffle_ps(sb, sb, 0xaa), d2)));
  storePair(base + p.b[3], base + q.b[3], _mm256_sub_ps(b3, _mm256_mul_ps(_mm256_shuffle_ps(sb, sb, 0xff), d3)));
}

/// Items [begin, end) of the colour whose blocks start at `first`: item j < pairs is the pair of blocks
/// first + 2 j, 2 j + 1 through the AVX2 kernel; an odd last block is the item after the pairs, through the SSE
/// kernel (VEX-encoded here). The odd block shares no vertex with the pairs (one colour).
template <bool kLambda>
DRAPE_TARGET_AVX2 void solveColourAvx2(Index begin, Index end, const DistanceBlock<float>* blocks, Index first,
                                       Index pairs, const float* massA, const float* massB, float alphaTilde,
                                       float* lambda, Vec4<float>* xw) {
  constexpr Index kLanes = DistanceBlock<float>::kLanes;
  for (Index j = begin; j < end; ++j) {
    const Index k = first + 2 * j;
    if (j < pairs)
      solveDistanceBlockPair<kLambda>(blocks + k, massA + k * kLanes, massB + k * kLanes, alphaTilde,
                                      kLambda ? lambda + k * kLanes : nullptr, xw);
    else
      solveDistanceBlock<kLambda>(blocks[k], massA + k * kLanes, massB + k * kLanes, _mm_set1_ps(alphaTilde),
                                  kLambda ? lambda + k * kLanes : nullptr, xw);
  }
}
#endif

}  // namespace detail

/// How many items colour c of a set has for the kernel of `level` (simdLevelFor): its constraints (scalar), its
/// blocks (SSE2), or its pairs of blocks and an odd last block (AVX2). Threads share a colour's work in whole
/// items, which write disjoint vertices, so the result does not depend on their number.
template <Scalar S>
Index colourItems(const DistanceSet<S>& set, const DistanceBlocks<S>& blocks, Index c, SimdLevel level) {
  if (level == SimdLevel::Scalar) return set.colourOffsets[c + 1] - set.colourOffsets[c];
  const Index count = blocks.blockOffsets[c + 1] - blocks.blockOffsets[c];
  return level == SimdLevel::Avx2 ? (count + 1) / 2 : count;
}

/// Items [begin, end) of colour c (colourItems) of one pass over `set`, on packed positions xw (x, y, z, 0)
/// with the vertices' inverse masses; the float SIMD kernels read the same constraints from `blocks` (built
/// from `set`, its masses gathered). `level` must come from simdLevelFor. alphaTilde = compliance / h^2; lambda
/// holds the accumulated multipliers of this substep (zeroed at its start), blocks.lambdaCount(set) of them; it
/// may be null when kLambda is false. kLambda false drops the multipliers: exact when they cannot matter, i.e.
/// for rigid constraints (alphaTilde 0) or a single pass per substep (lambda is 0 on entry and never read
/// again), and it saves a load, a store and a multiply per constraint. The levels give the same bits, but the
/// multipliers are kept per lane by the SIMD kernels and per constraint by the scalar one, so one lambda array
/// serves one level. Colours must be solved in order, each one whole before the next starts.
template <bool kLambda, Scalar S>
void solveDistanceColour(Index begin, Index end, Index c, const DistanceSet<S>& set, const DistanceBlocks<S>& blocks,
                         S alphaTilde, S* lambda, Vec4<S>* xw, const S* invMass, SimdLevel level) {
  if constexpr (std::is_same_v<S, float>) {
    [[maybe_unused]] constexpr Index kLanes = DistanceBlock<S>::kLanes;
#if DRAPE_AVX2
    if (level == SimdLevel::Avx2) {
      const Index first = blocks.blockOffsets[c], pairs = (blocks.blockOffsets[c + 1] - first) / 2;
      detail::solveColourAvx2<kLambda>(begin, end, blocks.blocks.data(), first, pairs, blocks.massA.data(),
                                       blocks.massB.data(), alphaTilde, lambda, xw);
      return;
    }
#endif
#if DRAPE_SSE2
    if (level == SimdLevel::Sse2) {
      const Index first = blocks.blockOffsets[c];
      const __m128 alpha = _mm_set1_ps(alphaTilde);
      for (Index k = first + begin; k < first + end; ++k)
        detail::solveDistanceBlock<kLambda>(blocks.blocks[k], blocks.massA.data() + k * kLanes,
                                            blocks.massB.data() + k * kLanes, alpha,
                                            kLambda ? lambda + k * kLanes : nullptr, xw);
      return;
    }
#endif
  }
  const auto* pairs = set.pairs.data();
  const S* rest = set.restLength.data();
  const Index first = set.colourOffsets[c];
  for (Index k = first + begin; k < first + end; ++k)
    detail::solveDistance<kLambda>(pairs[k][0], pairs[k][1], rest[k], alphaTilde, kLambda ? lambda + k : nullptr, xw,
                                   invMass);
}

/// One whole pass over `set` on the calling thread (solveDistanceColour for every colour in turn), with the
/// kernel of `level` (bestSimdLevel() by default).
template <bool kLambda, Scalar S>
void solveDistanceSet(const DistanceSet<S>& set, const DistanceBlocks<S>& blocks, S alphaTilde, S* lambda,
                      Vec4<S>* xw, const S* invMass, SimdLevel level = bestSimdLevel()) {
  level = simdLevelFor<S>(level);
  for (Index c = 0; c < set.colourCount(); ++c)
    solveDistanceColour<kLambda>(0, colourItems(set, blocks, c, level), c, set, blocks, alphaTilde, lambda, xw,
                                 invMass, level);
}

/// A vertex attached to a target point (in the cloth's local frame).
template <Scalar S> struct PinTarget {
  Index vertex;
  Vec3<S> target;
};

/// Pins on packed positions: a vertex of inverse mass 0 is placed on its target (kinematic); any other is
/// pulled toward it by a zero-length XPBD distance constraint. Serial: two pins may hold the same vertex. With
/// kRecord, each pull is added to `external` as an external push on a vertex that started the substep at
/// `start` (Settings::keepAngularMomentum).
template <bool kRecord = false, Scalar S>
void solvePins(const PinTarget<S>* pins, Index count, S alphaTilde, S* lambda, Vec4<S>* xw, const S* invMass,
               SpinSums* external = nullptr, const Vec3<S>* start = nullptr) {
  for (Index k = 0; k < count; ++k) {
    const Index i = pins[k].vertex;
    auto x = xw[i].template head<3>();
    const S w = invMass[i];
    if (w == S(0)) {
      x = pins[k].target;
      continue;
    }
    const Vec3<S> d = x - pins[k].target;
    const S len = d.norm();
    if (len <= S(0)) continue;
    const S dLambda = (-len - alphaTilde * lambda[k]) / (w + alphaTilde);
    lambda[k] += dLambda;
    const Vec3<S> pull = (w * dLambda / len) * d;
    x += pull;
    if constexpr (kRecord) external->addExternal(start[i], pull, w);
  }
}

}  // namespace drape
