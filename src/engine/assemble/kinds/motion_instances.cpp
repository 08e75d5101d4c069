// [NV-motion] Top levels built with VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV: the instances are
// VkAccelerationStructureMotionInstanceNV (or pointers to their members, the type in the low 4 bits), stored as
// format::MotionInstanceRecord whose boxes hold the instance over the whole time range [0, 1].
//   gather: every instance of a valid type whose reference names a bottom-level structure, in instance order.
//   refit:  the record rebuilt from the update's instance of the same index.
//   probe:  active = a valid type and a reference not 0.
#include <cstddef>
#include <cstring>
#include <optional>

#include "engine/assemble/kinds/kind.hpp"
#include "engine/assemble/refit_tree.hpp"
#include "engine/format/motion.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/input/motion_inputs.hpp"

namespace vkas {

using namespace format;

namespace {

// The record of active motion instance `instanceId` and the box that holds it over [0, 1]; the same for a build and
// a refit.
void makeMotionInstanceRecord(const motion::RawMotionInstance& inst, uint32_t instanceId, const std::byte* blas,
                              MotionInstanceRecord& rec, Aabb& box) {
    std::memset(&rec, 0, sizeof rec);
    if (inst.type == motion::kStatic) {
        std::memcpy(rec.base.objectToWorld, inst.staticTransform, sizeof rec.base.objectToWorld);
        Affine3x4d inv;
        invertAffine(affineFromFloat(inst.staticTransform), inv);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) rec.base.worldToObject[r][c] = float(inv.m[r][c]);
    } else {
        rec.base.motionType = inst.type;
        std::memcpy(rec.motion, inst.motion, sizeof rec.motion);
        if (inst.type == motion::kMatrix) std::memset(rec.motion + 24, 0, 8 * sizeof(float));
        motion::instanceTransformsAt(rec.base, 0.0f, rec.base.objectToWorld, rec.base.worldToObject);
    }
    rec.base.customIndexAndMask = inst.customIndexAndMask;
    rec.base.sbtOffsetAndFlags = inst.sbtOffsetAndFlags;
    rec.base.reference = inst.reference;
    rec.base.instanceId = instanceId;
    // The bottom level's bounds; an empty one is a point at the object-space origin (degenerate instance).
    const Header* h = header(blas);
    double boxLo[3] = {0, 0, 0}, boxHi[3] = {0, 0, 0};
    if (h->bounds[0] <= h->bounds[3] && h->bounds[1] <= h->bounds[4] && h->bounds[2] <= h->bounds[5])
        for (int c = 0; c < 3; ++c) boxLo[c] = h->bounds[c], boxHi[c] = h->bounds[3 + c];
    double lo[3], hi[3];
    motion::instanceBounds(inst.type, inst.staticTransform, inst.motion, boxLo, boxHi, lo, hi);
    box.lower = {roundDown(lo[0]), roundDown(lo[1]), roundDown(lo[2])};
    box.upper = {roundUp(hi[0]), roundUp(hi[1]), roundUp(hi[2])};
}

uint32_t gatherMotionInstances(const BuildJob& job, PrimRef* refs, std::byte* tempBytes) {
    auto* temp = reinterpret_cast<MotionInstanceRecord*>(tempBytes);
    const auto& info = *job.info;
    if (info.geometryCount == 0 || job.ranges[0].primitiveCount == 0) return 0;
    uint32_t n = 0;
    motion::MotionInstanceSource source(buildGeometry(info, 0).geometry.instances, job.ranges[0]);
    for (uint32_t i = 0; i < source.count(); ++i) {
        motion::RawMotionInstance inst;
        if (!source.fetch(i, inst) || inst.reference == 0) continue;  // inactive: still counted in instance ids
        const std::byte* blas = job.resolver ? job.resolver(inst.reference) : nullptr;
        if (!blas) continue;  // not a structure (invalid usage, reported by validation)
        MotionInstanceRecord rec;
        Aabb b;
        makeMotionInstanceRecord(inst, i, blas, rec, b);
        temp[n] = rec;
        setPrimRef(refs[n], n, b);
        ++n;
    }
    return n;
}

struct MotionInstanceRefitter {
    static constexpr size_t kSize = sizeof(MotionInstanceRecord);
    const RefitJob& job;
    std::optional<motion::MotionInstanceSource> source;
    explicit MotionInstanceRefitter(const RefitJob& j) : job(j) {
        if (j.info->geometryCount == 1)
            source.emplace(buildGeometry(*j.info, 0).geometry.instances, j.ranges[0]);
    }
    void operator()(const std::byte* in, std::byte* out, Aabb& box) {
        MotionInstanceRecord rec;
        std::memcpy(&rec, in, sizeof rec);
        motion::RawMotionInstance inst;
        if (source && rec.base.instanceId < source->count() && source->fetch(rec.base.instanceId, inst) &&
            inst.type <= motion::kSrt && inst.reference != 0) {
            const std::byte* blas = job.resolver ? job.resolver(inst.reference) : nullptr;
            if (blas) {
                const uint32_t id = rec.base.instanceId;
                Aabb b;
                makeMotionInstanceRecord(inst, id, blas, rec, b);
                box.extend(b);
            }
        }
        std::memcpy(out, &rec, sizeof rec);
    }
};

struct MotionInstanceProbe {
    std::optional<motion::MotionInstanceSource> instances;
    explicit MotionInstanceProbe(const RefitJob& job) {
        if (job.info->geometryCount == 1)
            instances.emplace(buildGeometry(*job.info, 0).geometry.instances, job.ranges[0]);
    }
    refit::RecordKey key(const std::byte* records, uint64_t j) const {
        return {0, reinterpret_cast<const InstanceRecord*>(records + j * sizeof(MotionInstanceRecord))->instanceId};
    }
    void probe(uint32_t, uint32_t i, bool& active, bool& storable) {
        motion::RawMotionInstance inst;
        active = storable =
            instances && instances->fetch(i, inst) && inst.type <= motion::kSrt && inst.reference != 0;
    }
};

void refitMotionInstances(const RefitJob& job) { refit::runRefit<refit::PerRecord<MotionInstanceRefitter>>(job); }

ActivityViolation motionInstanceActivity(const RefitJob& job) {
    MotionInstanceProbe probe(job);
    return refit::checkActivity(job, probe);
}

}  // namespace

const PrimitiveKind kMotionInstanceKind{gatherMotionInstances, refitMotionInstances, motionInstanceActivity};

}  // namespace vkas
