// docs/design.md §4, propagation (the CPU twin: propagateCorrections in include/drape/collision/response.hpp),
// one dispatch per ring: a free vertex not in contact gathers from its neighbours in the ring before (ring 1: the
// contact vertices that gained normal velocity) the mean of their corrections times the weight, along their
// mean normal, and takes of it only what removes its own approach toward the solid (relative to the solids'
// speed along that normal). Each vertex writes only itself, and gathers its neighbours in the asset's order, so
// the sums are the CPU's.
layout(local_size_x = DRAPE_WORKGROUP) in;
layout(std430, binding = DRAPE_B_VELOCITIES) buffer Velocities { vec4 v[]; };
layout(std430, binding = DRAPE_B_POSITIONS) readonly buffer Positions { vec4 x[]; };
layout(std430, binding = DRAPE_B_CONTACTS) readonly buffer Contacts { Contact contacts[]; };
layout(std430, binding = DRAPE_B_NEIGHBOUR_OFFSETS) readonly buffer NeighbourOffsets { uint neighbourOffsets[]; };
layout(std430, binding = DRAPE_B_NEIGHBOURS) readonly buffer Neighbours { uint neighbours[]; };
layout(std430, binding = DRAPE_B_PROPAGATION) buffer Propagation { Ring rings[]; };
layout(location = DRAPE_U_COUNT) uniform uint count;
layout(location = DRAPE_U_RING) uniform uint ring;
layout(location = DRAPE_U_WEIGHT) uniform float weight;

void main() {
  const uint j = gl_GlobalInvocationID.x;
  if (j >= count) return;
  if (contacts[j].slots.x != 0u || x[j].w == 0.0) return;
  if (ring > 1u && rings[j].reached != 0u) return;  // settled in an earlier ring
  precise vec3 normalSum = vec3(0.0);
  precise float speedSum = 0.0, amountSum = 0.0;
  int found = 0;
  for (uint k = neighbourOffsets[j]; k < neighbourOffsets[j + 1u]; ++k) {
    const uint i = neighbours[k];
    if (ring == 1u) {
      // Only the fields read here are loaded (a whole record is 192 bytes).
      const uint slots = contacts[i].slots.x;
      const float gained = contacts[i].normalDv.x;
      if (slots == 0u || gained <= 0.0) continue;
      // ContactBuffer::normal: the slots' normals weighted by their corrections, normalised (the first slot's if
      // none); ContactBuffer::solidVelocity: the first slot's.
      precise vec3 weighted = vec3(0.0);
      for (uint k = 0u; k < slots; ++k) {
        const vec4 nk = contacts[i].normal[k];
        weighted = weighted + nk.w * nk.xyz;
      }
      precise const float len = length3(weighted);
      precise const vec3 ni = len > 0.0 ? weighted / len : contacts[i].normal[0].xyz;
      normalSum = normalSum + ni;
      speedSum = speedSum + dot3(ni, contacts[i].velocity[0].xyz);
      amountSum = amountSum + gained;
    } else {
      const Ring r = rings[i];
      if (r.reached != ring - 1u || r.amount <= 0.0) continue;
      normalSum = normalSum + r.normal.xyz;
      speedSum = speedSum + r.normal.w;
      amountSum = amountSum + r.amount;
    }
    ++found;
  }
  if (found == 0) return;
  rings[j].reached = ring;
  rings[j].amount = 0.0;
  precise const float len = length3(normalSum);
  if (len <= 0.0) return;
  precise const float inv = 1.0 / float(found);
  precise const vec3 nj = normalSum / len;
  precise const float vcn = speedSum / len;  // the solids' speed along nj (propagateRing)
  const vec3 vj = v[j].xyz;
  precise const float approach = -(dot3(nj, vj) - vcn);
  precise const float give = weight * amountSum * inv;
  if (approach > 0.0) v[j] = vec4(vj + min(approach, give) * nj, 0.0);
  rings[j].amount = give;
  rings[j].normal = vec4(nj, vcn);
}
