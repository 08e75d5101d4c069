// Top levels (VK_GEOMETRY_TYPE_INSTANCES_KHR) without motion: format::InstanceRecord, the instance's fields, its
// world-to-object transform (the double inverse, rounded) and its world-space box.
//   gather: every instance whose reference names a bottom-level structure (0: inactive; anything else that names
//           nothing: invalid usage, reported by validation), in instance order; instanceId keeps its index.
//   refit:  the record rebuilt from the update's instance of the same index; the bottom level's new bounds count.
//   probe:  active = reference not 0.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <optional>

#include "engine/assemble/kinds/kind.hpp"
#include "engine/assemble/refit_tree.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/input/instances.hpp"

namespace vkas {

using namespace format;

namespace {

Aabb instanceWorldBounds(const RawInstance& inst, const std::byte* blas) {
    const Header* h = header(blas);
    Affine3x4d m = affineFromFloat(inst.transform);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    bool empty = !(h->bounds[0] <= h->bounds[3] && h->bounds[1] <= h->bounds[4] && h->bounds[2] <= h->bounds[5]);
    if (empty) {  // a degenerate instance: a point at the instance origin
        for (int c = 0; c < 3; ++c) lo[c] = hi[c] = m.m[c][3];
    } else {
        for (int corner = 0; corner < 8; ++corner) {
            double p[3] = {h->bounds[(corner & 1) ? 3 : 0], h->bounds[(corner & 2) ? 4 : 1],
                           h->bounds[(corner & 4) ? 5 : 2]};
            double q[3];
            applyAffine(m, p, q);
            for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], q[c]), hi[c] = std::max(hi[c], q[c]);
        }
    }
    Aabb b;
    b.lower = {roundDown(lo[0]), roundDown(lo[1]), roundDown(lo[2])};
    b.upper = {roundUp(hi[0]), roundUp(hi[1]), roundUp(hi[2])};
    return b;
}

// The record of active instance `instanceId` and its world-space box (the bottom level `blas`'s bounds
// transformed, rounded outwards); the same for a build and a refit.
void makeInstanceRecord(const RawInstance& inst, uint32_t instanceId, const std::byte* blas, InstanceRecord& rec,
                        Aabb& box) {
    std::memset(&rec, 0, sizeof rec);
    std::memcpy(rec.objectToWorld, inst.transform, sizeof rec.objectToWorld);
    Affine3x4d inv;
    invertAffine(affineFromFloat(inst.transform), inv);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) rec.worldToObject[r][c] = float(inv.m[r][c]);
    rec.customIndexAndMask = inst.customIndexAndMask;
    rec.sbtOffsetAndFlags = inst.sbtOffsetAndFlags;
    rec.reference = inst.reference;
    rec.instanceId = instanceId;
    box = instanceWorldBounds(inst, blas);
}

uint32_t gatherInstances(const BuildJob& job, PrimRef* refs, std::byte* tempBytes) {
    auto* temp = reinterpret_cast<InstanceRecord*>(tempBytes);
    const auto& info = *job.info;
    if (info.geometryCount == 0 || job.ranges[0].primitiveCount == 0) return 0;
    uint32_t n = 0;
    InstanceSource source(buildGeometry(info, 0).geometry.instances, job.ranges[0]);
    for (uint32_t i = 0; i < source.count(); ++i) {
        RawInstance inst = source.fetch(i);
        if (inst.reference == 0) continue;  // inactive instance: still counted in instance ids
        const std::byte* blas = job.resolver ? job.resolver(inst.reference) : nullptr;
        if (!blas) continue;  // not a structure (invalid usage, reported by validation)
        InstanceRecord rec;
        Aabb b;
        makeInstanceRecord(inst, i, blas, rec, b);
        temp[n] = rec;
        setPrimRef(refs[n], n, b);
        ++n;
    }
    return n;
}

struct InstanceRefitter {
    static constexpr size_t kSize = sizeof(InstanceRecord);
    const RefitJob& job;
    std::optional<InstanceSource> source;
    explicit InstanceRefitter(const RefitJob& j) : job(j) {
        if (j.info->geometryCount == 1) source.emplace(buildGeometry(*j.info, 0).geometry.instances, j.ranges[0]);
    }
    void operator()(const std::byte* in, std::byte* out, Aabb& box) {
        InstanceRecord rec;
        std::memcpy(&rec, in, sizeof rec);
        if (source && rec.instanceId < source->count()) {
            const RawInstance inst = source->fetch(rec.instanceId);
            const std::byte* blas = inst.reference && job.resolver ? job.resolver(inst.reference) : nullptr;
            if (blas) {  // otherwise invalid (inactive now, or not a structure): kept with an empty box
                const uint32_t id = rec.instanceId;
                Aabb b;
                makeInstanceRecord(inst, id, blas, rec, b);
                box.extend(b);
            }
        }
        std::memcpy(out, &rec, sizeof rec);
    }
};

struct InstanceProbe {
    std::optional<InstanceSource> instances;
    explicit InstanceProbe(const RefitJob& job) {
        if (job.info->geometryCount == 1) instances.emplace(buildGeometry(*job.info, 0).geometry.instances, job.ranges[0]);
    }
    refit::RecordKey key(const std::byte* records, uint64_t j) const {
        return {0, reinterpret_cast<const InstanceRecord*>(records + j * sizeof(InstanceRecord))->instanceId};
    }
    void probe(uint32_t, uint32_t i, bool& active, bool& storable) {
        active = storable = instances && instances->fetch(i).reference != 0;
    }
};

void refitInstances(const RefitJob& job) { refit::runRefit<refit::PerRecord<InstanceRefitter>>(job); }

ActivityViolation instanceActivity(const RefitJob& job) {
    InstanceProbe probe(job);
    return refit::checkActivity(job, probe);
}

}  // namespace

const PrimitiveKind kInstanceKind{gatherInstances, refitInstances, instanceActivity};

}  // namespace vkas
