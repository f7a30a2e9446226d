#pragma once
// A face pass shared by a team with the one-thread pass's result, bit for bit (docs/design.md §12, "The face pass
// on several threads"). A face reads and moves its corners, so the pass's result depends on the order in which
// faces that share a corner are visited, and on nothing else. The faces are cut into segments of consecutive
// indices, dealt out to the threads in turn; each face waits until every face before it that shares a corner with
// it and lies in another thread's segment is done. Faces that share a corner are then visited in index order, as
// on one thread. A sheet numbered row by row is a sequence of runs (consecutive faces share a corner within a row,
// not across its end): each run is cut into one segment per thread, so thread t takes part t of every row, waits
// at its start for part t - 1 of the same row and otherwise runs beside the others, a row behind its neighbour.
// Segments are ranges of face indices, so the plan, made once per mesh and team, serves every list of faces in
// ascending order.

#include <drape/collision/response.hpp>
#include <drape/detail/simd.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <thread>
#include <vector>

namespace drape {

namespace detail {
inline constexpr int kSpinTurns = 256;  // pauses before a waiting thread yields
/// One thread's place in a wave: every face of its segments below this index is done. A cache line each, so that
/// one thread's stores do not take the line another thread's place sits on.
struct alignas(64) WavePlace {
  std::atomic<Index> done{0};
};
/// One turn of a wait: a pause while the wait is young, then the processor given up, so that a team with more
/// threads than cores lets the thread it waits for run.
inline void spinPause(int& turns) {
  if (turns < kSpinTurns) {
    ++turns;
#if DRAPE_SSE2
    _mm_pause();
#endif
  } else {
    std::this_thread::yield();
  }
}
}  // namespace detail

/// The gate of one thread in a wave (projectFaceContactsAs's `gate`): which positions of the list it visits, and
/// the wait. The list holds face indices in ascending order (`items`; null: every face, position = index).
class WaveGate {
 public:
  WaveGate(const Index* need, const Index* segments, Index segmentCount, detail::WavePlace* places, int threads,
           int self, const Index* items)
      : need_(need), segments_(segments), places_(places), items_(items), segmentCount_(segmentCount),
        threads_(threads), self_(self) {}

  Index first(Index count) { return enter(0, count); }
  /// The position after f: the next in this segment, else the first in this thread's next segment that holds one.
  /// Published now and then, at the end of a segment, and when waiting, so that a thread that waits never waits
  /// on one that waits on it (the one at the lowest face always has all it needs).
  Index next(Index f, Index count) {
    const Index g = f + 1;
    if (g < count && face(g) < segmentEnd_) {
      if ((g & (kPublishEvery - 1)) == 0) publish(face(g));
      ++visited_;
      return g;
    }
    segment_ += threads_;
    return enter(g, count);
  }
  /// Waits until every face before f's that shares a corner with it, in another thread's segment, is done.
  void wait(Index f) {
    const Index needed = need_[face(f)];
    if (needed < seen_) return;
    publish(face(f));
    for (int turns = 0;;) {
      Index least = kAll;
      for (int t = 0; t < threads_; ++t)
        if (t != self_) least = std::min(least, places_[t].done.load(std::memory_order_acquire));
      seen_ = least;
      if (needed < seen_) return;
      detail::spinPause(turns);
    }
  }
  /// How many faces of the list this thread visited (after the pass).
  Index share(Index) const { return visited_; }

 private:
  static constexpr Index kPublishEvery = 16;  // a power of two
  static constexpr Index kAll = std::numeric_limits<Index>::max();
  Index face(Index f) const { return items_ != nullptr ? items_[f] : f; }
  /// From position g on, the first face of the list in this thread's segment `segment_` or a later one of its own,
  /// or count (then every face of this thread is done).
  Index enter(Index g, Index count) {
    for (; segment_ < segmentCount_; segment_ += threads_) {
      const Index start = segments_[segment_];
      segmentEnd_ = segments_[segment_ + 1];
      while (g < count && face(g) < start) ++g;  // the others' segments between
      if (g == count) break;
      if (face(g) < segmentEnd_) {
        publish(face(g));
        ++visited_;
        return g;
      }
    }
    publish(kAll);
    return count;
  }
  void publish(Index face) { places_[self_].done.store(face, std::memory_order_release); }

  const Index* need_;
  const Index* segments_;
  detail::WavePlace* places_;
  const Index* items_;
  Index segmentCount_;
  int threads_, self_;
  Index segment_ = self_;
  Index segmentEnd_ = 0;
  Index seen_ = 0;  // the least face another thread had published, as last read (all are at least 0)
  Index visited_ = 0;
};

/// The plan of a wave over the faces of one mesh for a team (the segments and, for each face, the last face before
/// it in another thread's segment that shares a corner), and the threads' places. Planned by one thread; run by
/// all.
class FaceWave {
 public:
  FaceWave() = default;
  /// A copy (a copied solver's) plans anew.
  FaceWave(const FaceWave&) {}
  FaceWave& operator=(const FaceWave&) {
    forget();
    return *this;
  }
  FaceWave(FaceWave&&) = default;
  FaceWave& operator=(FaceWave&&) = default;

  /// Readies a pass over `count` faces of `triangles` for `threads` threads, planned once per mesh and team; false
  /// where the pass is too short to share or the mesh is not numbered in long enough runs (then it runs on one
  /// thread).
  bool ready(Index count, const std::vector<std::array<Index, 3>>& triangles, Index vertexCount, int threads) {
    if (threads < 2 || count < kShortest) return false;
    if (&triangles != mesh_ || Index(triangles.size()) != faces_ || threads != threads_) {
      mesh_ = &triangles;
      faces_ = Index(triangles.size());
      threads_ = threads;
      planned_ = plan(triangles, vertexCount);
    }
    if (!planned_) return false;
    if (placeCount_ < threads_) {
      places_ = std::make_unique<detail::WavePlace[]>(std::size_t(threads_));
      placeCount_ = threads_;
    }
    for (int t = 0; t < threads_; ++t)
      places_[std::size_t(t)].done.store(segments_[std::size_t(t)], std::memory_order_relaxed);
    return true;
  }
  /// The gate of thread `self` over a list of ascending face indices (null: every face).
  WaveGate gate(int self, const Index* items) {
    return WaveGate(need_.data(), segments_.data(), Index(segments_.size()) - 1, places_.get(), threads_, self,
                    items);
  }
  /// The last face before f, in another thread's segment, that shares a corner with it (-1: none).
  Index need(Index f) const { return need_[std::size_t(f)]; }
  /// The segments' bounds: segment k is faces [bounds[k], bounds[k + 1]) and belongs to thread k % threads.
  const std::vector<Index>& segments() const { return segments_; }
  /// Forgets the plan (the mesh changed).
  void forget() { mesh_ = nullptr; }

 private:
  static bool shareCorner(const std::array<Index, 3>& a, const std::array<Index, 3>& b) {
    for (Index u : a)
      for (Index v : b)
        if (u == v) return true;
    return false;
  }
  bool plan(const std::vector<std::array<Index, 3>>& triangles, Index vertexCount) {
    // The runs: maximal ranges of faces each sharing a corner with the one before it (the rows of a sheet).
    std::vector<Index> runStarts{0};
    for (Index f = 1; f < faces_; ++f)
      if (!shareCorner(triangles[std::size_t(f - 1)], triangles[std::size_t(f)])) runStarts.push_back(f);
    runStarts.push_back(faces_);
    std::vector<Index> lengths;
    for (std::size_t r = 0; r + 1 < runStarts.size(); ++r) lengths.push_back(runStarts[r + 1] - runStarts[r]);
    std::nth_element(lengths.begin(), lengths.begin() + std::ptrdiff_t(lengths.size() / 2), lengths.end());
    // Runs too short to cut in one part per thread, or too few of them: one thread.
    if (lengths[lengths.size() / 2] < kShortestPart * Index(threads_) || lengths.size() < 4) return false;
    segments_.clear();
    for (std::size_t r = 0; r + 1 < runStarts.size(); ++r) {
      const Index begin = runStarts[r], length = runStarts[r + 1] - begin;
      for (int t = 0; t < threads_; ++t) segments_.push_back(begin + length * t / threads_);
    }
    segments_.push_back(faces_);
    // need[f]: the last face before f, in another thread's segment, that shares a corner with it. Per vertex the
    // last face seen, its segment's owner, and the last before it in another owner's segment.
    struct Seen {
      Index last = -1, other = -1;
      int owner = -1;
    };
    std::vector<Seen> seen(static_cast<std::size_t>(vertexCount));
    need_.assign(std::size_t(faces_), -1);
    std::size_t segment = 0;
    for (Index f = 0; f < faces_; ++f) {
      while (segments_[segment + 1] <= f) ++segment;
      const int owner = int(segment % std::size_t(threads_));
      Index needed = -1;
      for (Index v : triangles[std::size_t(f)]) {
        Seen& s = seen[std::size_t(v)];
        needed = std::max(needed, s.owner != owner ? s.last : s.other);
        if (s.owner != owner) s.other = s.last, s.owner = owner;
        s.last = f;
      }
      need_[std::size_t(f)] = needed;
    }
    return true;
  }

  static constexpr Index kShortest = 1024;    // shorter passes run on one thread
  static constexpr Index kShortestPart = 16;  // faces in a thread's part of a run
  std::vector<Index> need_, segments_;
  std::unique_ptr<detail::WavePlace[]> places_;
  int placeCount_ = 0;
  Index faces_ = 0;
  int threads_ = 1;
  const void* mesh_ = nullptr;
  bool planned_ = false;
};

}  // namespace drape
