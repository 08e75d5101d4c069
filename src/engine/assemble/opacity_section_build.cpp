#include "engine/util/host_memory.hpp"
#include "engine/assemble/opacity_section_build.hpp"

#include <cstring>
#include <vector>

namespace vkas {

using namespace format;

namespace {

constexpr uint64_t kFailed = UINT64_MAX;

uint64_t saturatingAdd(uint64_t a, uint64_t b) { return a > UINT64_MAX - b ? UINT64_MAX : a + b; }

// One geometry's block, laid out (and, when `out` is not null, written) at `at`. Returns its end, or kFailed.
class GeometryWriter {
public:
    GeometryWriter(const TrianglesOpacityMicromap& omm, uint32_t primitiveCount, MicromapResolver resolve)
        : omm_(omm), count_(primitiveCount) {
        micromap_ = omm.micromap != VK_NULL_HANDLE && resolve ? resolve(uint64_t(omm.micromap)) : nullptr;
    }

    uint64_t write(std::byte* base, uint64_t at, uint64_t limit) {
        const uint64_t primsAt = at + sizeof(OpacityGeometry);
        const uint64_t dataAt = primsAt + uint64_t(count_) * sizeof(OpacityPrimitive);
        if (dataAt + kSpecialStateBytes > limit) return kFailed;
        const bool named = omm_.micromap != VK_NULL_HANDLE;
        if (named && !micromap_) return kFailed;
        const uint32_t triangleCount = micromap_ ? micromapHeader(micromap_)->triangleCount : 0;
        // The data slot of each micromap triangle the geometry uses, in order of first use (UINT32_MAX: not yet).
        HostVector<uint32_t> slot(triangleCount, UINT32_MAX);
        uint64_t dataSize = kSpecialStateBytes;
        if (base)
            for (uint32_t k = 0; k < kSpecialStateBytes; ++k) base[dataAt + k] = std::byte(k);
        for (uint32_t i = 0; i < count_; ++i) {
            const OpacityIndex index = opacityIndexOf(omm_, i);
            OpacityPrimitive p;
            if (index.special) {
                p = {specialState(index.specialIndex), 0, uint16_t(kOpacityFormat4State)};
            } else {
                // "If micromap is VK_NULL_HANDLE, then every value read from indexBuffer must be one of the values in
                // VkOpacityMicromapSpecialIndexEXT."
                if (index.triangle >= triangleCount) return kFailed;
                const MicromapTriangle& t = micromapTriangles(micromap_)[index.triangle];
                uint32_t& s = slot[index.triangle];
                if (s == UINT32_MAX) {
                    const uint64_t bytes = opacityTriangleDataBytes(t.subdivisionLevel, t.format);
                    if (dataSize > UINT32_MAX || dataAt + dataSize + bytes > limit) return kFailed;
                    s = uint32_t(dataSize);
                    if (base) std::memcpy(base + dataAt + dataSize, micromapData(micromap_) + t.dataOffset, bytes);
                    dataSize += bytes;
                }
                p = {s, t.subdivisionLevel, t.format};
            }
            if (base) std::memcpy(base + primsAt + uint64_t(i) * sizeof p, &p, sizeof p);
        }
        if (base) {
            OpacityGeometry g{count_, 0, dataAt, dataSize};
            std::memcpy(base + at, &g, sizeof g);
        }
        return dataAt + dataSize;
    }

private:
    const TrianglesOpacityMicromap& omm_;
    uint32_t count_;
    const std::byte* micromap_ = nullptr;
};

uint64_t layOut(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                const VkAccelerationStructureBuildRangeInfoKHR* ranges, MicromapResolver resolve, std::byte* base,
                uint64_t offset, uint64_t capacity) {
    const uint64_t limit = capacity == kFailed ? kFailed : offset + capacity;
    uint64_t at = alignOpacity(offset + 8ull * info.geometryCount);
    if (at > limit) return kFailed;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const auto& geom = buildGeometry(info, g);
        const TrianglesOpacityMicromap* omm =
            geom.geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR ? opacityMicromapOf(geom.geometry.triangles) : nullptr;
        uint64_t blockAt = 0;
        if (omm) {
            blockAt = at;
            const uint64_t end = GeometryWriter(*omm, ranges[g].primitiveCount, resolve).write(base, at, limit);
            if (end == kFailed) return kFailed;
            const uint64_t next = alignOpacity(end);
            if (base) std::memset(base + end, 0, next - end);
            at = next;
        }
        if (base) std::memcpy(base + offset + 8ull * g, &blockAt, sizeof blockAt);
    }
    if (base) std::memset(base + offset + 8ull * info.geometryCount, 0,
                          alignOpacity(offset + 8ull * info.geometryCount) - (offset + 8ull * info.geometryCount));
    return at - offset;
}

}  // namespace

bool hasOpacityMicromaps(const VkAccelerationStructureBuildGeometryInfoKHR& info) {
    if (info.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR) return false;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const auto& geom = buildGeometry(info, g);
        if (geom.geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR && opacityMicromapOf(geom.geometry.triangles))
            return true;
    }
    return false;
}

uint64_t opacityGeometryBound(const TrianglesOpacityMicromap* omm, uint64_t primitiveCount) {
    if (!omm) return 0;
    uint64_t bytes = sizeof(OpacityGeometry) + primitiveCount * sizeof(OpacityPrimitive) + kSpecialStateBytes + 7;
    forEachUsageCount(*omm, [&](const VkMicromapUsageEXT& u) {
        if (!isOpacityFormat(u.format) || u.subdivisionLevel > maxOpacitySubdivisionLevel(u.format)) return;
        bytes = saturatingAdd(bytes, uint64_t(u.count) * opacityTriangleDataBytes(u.subdivisionLevel, u.format));
    });
    return bytes;
}

uint64_t writeOpacitySection(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                             const VkAccelerationStructureBuildRangeInfoKHR* ranges, MicromapResolver resolve,
                             std::byte* base, uint64_t offset, uint64_t capacity) {
    // Lay out first, write second: a failure leaves nothing half-written behind.
    const uint64_t size = layOut(info, ranges, resolve, nullptr, offset, capacity);
    if (size == kFailed) return kFailed;
    return layOut(info, ranges, resolve, base, offset, capacity);
}

uint64_t opacitySectionSize(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                            const VkAccelerationStructureBuildRangeInfoKHR* ranges, MicromapResolver resolve) {
    return layOut(info, ranges, resolve, nullptr, 0, kFailed);
}

bool opacityPresenceMatches(const VkAccelerationStructureBuildGeometryInfoKHR& info, const std::byte* block) {
    const Header* h = header(block);
    if (h->geometryCount != info.geometryCount) return false;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const auto& geom = buildGeometry(info, g);
        const bool has = geom.geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR && opacityMicromapOf(geom.geometry.triangles);
        const bool had = h->opacityOffset != 0 && opacityGeometryBlocks(block)[g] != 0;
        if (has != had) return false;
    }
    return true;
}

}  // namespace vkas
