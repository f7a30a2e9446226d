#pragma once
// Two-way coupling on the GPU (docs/design.md §6, §9): the kernels and buffers that turn the cloth's contacts
// with dynamic solids into one force and torque per body. Each vertex's pushes are estimated by
// contact_forces.comp (coupling/contact_forces.hpp on the CPU), summed per body in double by body_sums.comp
// (coupling/body_sums.hpp), and the exchanges shared by share.comp (coupling/share.hpp). Only the sums, 192
// bytes a body, cross the bus. A scene without dynamic solids allocates none of the buffers.

#include <drape/coupling/body.hpp>
#include <drape/coupling/contact_forces.hpp>
#include <drape/coupling/share.hpp>
#include <drape/gpu/program.hpp>
#include <drape/gpu/shader_sources.hpp>
#include <drape/settings.hpp>

#include <algorithm>
#include <tuple>
#include <vector>

namespace drape::gpu {

class BodyCoupling {
 public:
  BodyCoupling()
      : contactForces_("contact_forces", shaders::contact_forces),
        bodySums_("body_sums", shaders::body_sums),
        share_("share", shaders::share) {}

  /// Sizes the buffers for a cloth of `vertices` vertices and `bodies` coupled bodies (once a scene has one).
  void reserve(std::size_t vertices, std::size_t bodies) {
    if (sums_.size() != bodies) {
      bodyData_.assign(std::vector<layout::Body>(bodies));
      sums_.assign(std::vector<layout::BodySum>(bodies));
      shares_.assign(std::vector<float>(bodies, 1.0f));
    }
    if (vStart_.size() != vertices) {
      const std::vector<layout::Vertex> zero(vertices, layout::Vertex{0, 0, 0, 0});
      vStart_.assign(zero);
      vPre_.assign(zero);
      lines_.assign(std::vector<layout::Lines>(vertices, layout::Lines{}));
      pushes_.assign(std::vector<layout::BodyPush>(vertices * layout::kContactSlots, layout::BodyPush{}));
      // A header, then room for one record per contact slot of every vertex.
      spacers_.assign(std::vector<layout::SpacerRecord>(vertices * layout::kContactSlots + 1, layout::SpacerRecord{}));
    }
  }
  void bind() const {
    sums_.bind(layout::kBodySums);
    shares_.bind(layout::kShares);
    vStart_.bind(layout::kVStart);
    vPre_.bind(layout::kVPre);
    lines_.bind(layout::kLines);
    pushes_.bind(layout::kPushes);
    spacers_.bind(layout::kSpacers);
  }
  /// The velocities at the start of the substep, and before the contacts act (what the estimators compare).
  void keepStartVelocities(const Buffer<layout::Vertex>& v, std::size_t count) const { copy(v, vStart_, count); }
  void keepPreContactVelocities(const Buffer<layout::Vertex>& v, std::size_t count) const { copy(v, vPre_, count); }

  /// The pushes every vertex wrote to bodies [first, first + count), summed per body in double (body_sums.comp:
  /// a workgroup per body, each reading every vertex's pushes) and read back.
  std::vector<layout::BodySum> sumPushes(int first, int count, unsigned vertexCount) {
    bodySums_.set(layout::kCount, vertexCount);
    glProgramUniform1i(bodySums_.id(), layout::kBody, first);
    glUseProgram(bodySums_.id());
    glDispatchCompute(GLuint(count), 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    return sums_.read(std::size_t(first), std::size_t(count));
  }

  /// Phase 2 (gatherContactForces on the CPU): the pushes of every vertex, summed per body; each body's exchange
  /// shared with the vertices that made it (share.comp scales those vertices' changes where a body took less than
  /// all); the forces, added to what `force` and `torque` hold (the repulsion's), applied to the bodies before
  /// they move and left in `force` and `torque`. `centres` are the bodies' centres (world), `origin` the cloth's.
  /// The pinches are listed in `spacers`, in the cloth's local frame, sorted by vertex and slot. `anchored` holds
  /// each body's anchors' supports (coupling::supportAnchors), shared with its pinches'.
  void gather(const std::vector<CoupledBody*>& bodies, const std::vector<Eigen::Vector3d>& centres,
              const Eigen::Vector3d& origin, const Settings& settings, float h, unsigned vertexCount,
              std::vector<Eigen::Vector3d>& force, std::vector<Eigen::Vector3d>& torque,
              std::vector<Spacer>& spacers, const std::vector<coupling::BodySums>& anchored) {
    upload(bodies, centres, origin);
    layout::SpacerRecord header{};
    header.body = std::int32_t(spacers_.size() - 1);
    spacers_.write({header});
    const ContactForce estimator = settings.contactForce;
    contactForces_.set(layout::kCount, vertexCount);
    contactForces_.set(layout::kStep, h);
    contactForces_.set(layout::kThickness, float(settings.thickness));
    glProgramUniform1i(contactForces_.id(), layout::kEstimator,
                       estimator == ContactForce::SubForce ? layout::kSubForce
                       : estimator == ContactForce::Energy ? layout::kEnergy
                                                           : layout::kImpulse);
    contactForces_.set(layout::kNormalOnly, unsigned(settings.normalForceOnly));
    contactForces_.set(layout::kPropagated, unsigned(coupling::passesPropagatedImpulse(settings)));
    contactForces_.dispatch(vertexCount);
    const std::size_t nb = bodies.size();
    const std::vector<layout::BodySum> sums = sumPushes(0, int(nb), vertexCount);
    readSpacers(spacers);
    std::vector<float> share(nb, 1.0f);
    bool partial = false;
    const auto vec = [](const double* v) { return Eigen::Vector3d(v[0], v[1], v[2]); };
    for (std::size_t b = 0; b < nb; ++b) {
      const layout::BodySum& sum = sums[b];
      CoupledBody& body = *bodies[b];
      const Eigen::Vector3d ef = vec(sum.exchangeForce), et = vec(sum.exchangeTorque);
      const double s = coupling::exchangeShare(body, ef, et, sum.exchangeForce[3]);
      Eigen::Vector3d f = force[b] + vec(sum.directForce) + s * ef;  // after the repulsion's
      Eigen::Vector3d t = torque[b] + vec(sum.directTorque) + s * et;
      // The pinches' supports, the GPU's and the anchors' (computed on the host), shared among them (addPinches).
      const coupling::BodySums& a = anchored[b];
      const double pinches = sum.pinchForce[3] + a.pinches;
      if (pinches > 0) {
        f += (vec(sum.pinchForce) + a.pinchForce) / pinches;
        t += (vec(sum.pinchTorque) + a.pinchTorque) / pinches;
      }
      body.applyForceAndTorque(f, t);
      force[b] = f;
      torque[b] = t;
      share[b] = float(s);
      partial = partial || s < 1;
    }
    if (!partial) return;
    shares_.write(share);
    share_.set(layout::kCount, vertexCount);
    share_.dispatch(vertexCount);
  }

 private:
  /// The pinches contact_forces.comp appended (after sumPushes' barrier), in the CPU's order.
  void readSpacers(std::vector<Spacer>& out) const {
    const std::size_t appended = std::size_t(spacers_.read(0, 1)[0].vertex);
    const std::size_t count = std::min(appended, spacers_.size() - 1);
    out.clear();
    if (count == 0) return;
    const std::vector<layout::SpacerRecord> records = spacers_.read(1, count);
    const auto vec = [](const float* v) { return Eigen::Vector3d(v[0], v[1], v[2]); };
    for (const layout::SpacerRecord& r : records) {
      Spacer p;
      p.vertex = r.vertex;
      p.body = r.body;
      p.other = r.other;
      p.slot = r.slot;
      p.onBody = vec(r.onBody);
      p.onOther = vec(r.onOther);
      p.normal = vec(r.normal);
      out.push_back(p);
    }
    std::sort(out.begin(), out.end(), [](const Spacer& a, const Spacer& b) {
      return std::tie(a.vertex, a.slot) < std::tie(b.vertex, b.slot);
    });
  }

  /// The bodies as the force kernel reads them: centres in the cloth's local frame, velocities, inverse mass and
  /// inverse inertia in world axes.
  void upload(const std::vector<CoupledBody*>& bodies, const std::vector<Eigen::Vector3d>& centres,
              const Eigen::Vector3d& origin) {
    std::vector<layout::Body> data(bodies.size());
    for (std::size_t b = 0; b < bodies.size(); ++b) {
      const CoupledBody& body = *bodies[b];
      const Vec3<float> c = (centres[b] - origin).cast<float>();
      const Vec3<float> lin = body.linearVelocity().cast<float>(), ang = body.angularVelocity().cast<float>();
      const Eigen::Matrix3f inertia = body.inverseInertiaWorld().cast<float>();
      layout::Body& d = data[b];
      d = layout::Body{{c.x(), c.y(), c.z(), float(body.inverseMass())}, {lin.x(), lin.y(), lin.z(), 0},
                       {ang.x(), ang.y(), ang.z(), 0}, {}};
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) d.inverseInertia[r][k] = inertia(r, k);
    }
    bodyData_.write(data);
    bodyData_.bind(layout::kBodies);
  }
  static void copy(const Buffer<layout::Vertex>& from, const Buffer<layout::Vertex>& to, std::size_t count) {
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glCopyNamedBufferSubData(from.id(), to.id(), 0, 0, GLsizeiptr(count * sizeof(layout::Vertex)));
  }

  Program contactForces_, bodySums_, share_;
  Buffer<layout::Vertex> vStart_, vPre_;  ///< velocities at the substep's start, before the contacts
  Buffer<layout::Lines> lines_;
  Buffer<layout::BodyPush> pushes_;
  Buffer<layout::SpacerRecord> spacers_;  ///< a header, then this substep's pinches
  Buffer<layout::Body> bodyData_;
  Buffer<layout::BodySum> sums_;
  Buffer<float> shares_;
};

}  // namespace drape::gpu
