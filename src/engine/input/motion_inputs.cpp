#include "engine/input/motion_inputs.hpp"

#include <cstring>

#include "engine/util/byte_io.hpp"
#include "engine/util/pnext_chain.hpp"

namespace vkas::motion {

MotionInstanceSource::MotionInstanceSource(const VkAccelerationStructureGeometryInstancesDataKHR& data,
                                           const VkAccelerationStructureBuildRangeInfoKHR& range)
    : data_(offsetAddress(data.data.hostAddress, range.primitiveOffset)),
      arrayOfPointers_(data.arrayOfPointers == VK_TRUE),
      count_(range.primitiveCount) {}

uintptr_t MotionInstanceSource::rawAddress(uint32_t i) const {
    if (arrayOfPointers_) return loadUnaligned<uintptr_t>(data_ + uint64_t(i) * sizeof(void*));
    return reinterpret_cast<uintptr_t>(data_ + uint64_t(i) * kMotionInstanceStride);
}

bool MotionInstanceSource::fetch(uint32_t i, RawMotionInstance& out) const {
    std::memset(&out, 0, sizeof out);
    const std::byte* payload;
    if (arrayOfPointers_) {
        const uintptr_t p = rawAddress(i);
        out.type = uint32_t(p & 0xF);
        out.flags = 0;
        payload = reinterpret_cast<const std::byte*>(p & ~uintptr_t(0xF));
        if (!payload) return false;
    } else {
        const std::byte* p = data_ + uint64_t(i) * kMotionInstanceStride;
        out.type = loadUnaligned<uint32_t>(p);
        out.flags = loadUnaligned<uint32_t>(p + 4);
        payload = p + 8;
    }
    switch (out.type) {
        case kStatic:
            std::memcpy(out.staticTransform, payload, 48);
            out.customIndexAndMask = loadUnaligned<uint32_t>(payload + 48);
            out.sbtOffsetAndFlags = loadUnaligned<uint32_t>(payload + 52);
            out.reference = loadUnaligned<uint64_t>(payload + 56);
            break;
        case kMatrix:  // transformT0 @0, transformT1 @48, custom|mask @96, sbt|flags @100, reference @104
            std::memcpy(out.motion, payload, 96);
            out.customIndexAndMask = loadUnaligned<uint32_t>(payload + 96);
            out.sbtOffsetAndFlags = loadUnaligned<uint32_t>(payload + 100);
            out.reference = loadUnaligned<uint64_t>(payload + 104);
            break;
        case kSrt:  // transformT0 @0, transformT1 @64, custom|mask @128, sbt|flags @132, reference @136
            std::memcpy(out.motion, payload, 128);
            out.customIndexAndMask = loadUnaligned<uint32_t>(payload + 128);
            out.sbtOffsetAndFlags = loadUnaligned<uint32_t>(payload + 132);
            out.reference = loadUnaligned<uint64_t>(payload + 136);
            break;
        default: out.reference = 0; break;  // invalid input (reported by validation): never hit
    }
    return true;
}

const VkAccelerationStructureGeometryMotionTrianglesDataNV* findMotionTriangles(
    const VkAccelerationStructureGeometryTrianglesDataKHR& triangles) {
    return findInChain<VkAccelerationStructureGeometryMotionTrianglesDataNV>(
        triangles.pNext, VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV);
}

}  // namespace vkas::motion
