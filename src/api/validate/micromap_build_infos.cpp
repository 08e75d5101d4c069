#include "engine/util/host_memory.hpp"
#include "api/validate/micromap_build_infos.hpp"

#include <algorithm>
#include <cstdio>
#include <vector>

#include "api/structure_bytes.hpp"
#include "api/deferred_operation.hpp"
#include "api/validate/parameters.hpp"
#include "engine/assemble/micromap_build.hpp"
#include "engine/format/micromap_layout.hpp"

namespace vkas {

namespace {

using ull = unsigned long long;

constexpr VkBuildMicromapFlagsEXT kKnownBuildFlags = VK_BUILD_MICROMAP_PREFER_FAST_TRACE_BIT_EXT |
                                                     VK_BUILD_MICROMAP_PREFER_FAST_BUILD_BIT_EXT |
                                                     VK_BUILD_MICROMAP_ALLOW_COMPACTION_BIT_EXT;
constexpr uint32_t kLevels = format::kMaxOpacity4StateSubdivisionLevel + 1;
static_assert(format::kMaxOpacity2StateSubdivisionLevel == format::kMaxOpacity4StateSubdivisionLevel);

// Triangles per (format, level): the usage counts' histogram, compared with the triangle array's.
struct Histogram {
    uint64_t count[2][kLevels] = {};
    static size_t formatIndex(uint32_t format) { return format == format::kOpacityFormat4State ? 1 : 0; }
    bool operator==(const Histogram& o) const { return std::equal(&count[0][0], &count[0][0] + 2 * kLevels, &o.count[0][0]); }
};

// The level rule of a format: 11654/11655 for usage counts, 11659/11660 for triangles.
bool checkLevel(Validator& v, uint32_t format, uint32_t level, const char* twoStateVuid, const char* fourStateVuid,
                const char* what, const char* name, unsigned long long index) {
    const uint32_t max = format::maxOpacitySubdivisionLevel(format);
    return v.check(level <= max, format == format::kOpacityFormat2State ? twoStateVuid : fourStateVuid,
                   "%s %s[%llu] has format %s and subdivisionLevel %u, more than maxOpacity%sStateSubdivisionLevel %u.",
                   name, what, index, format == format::kOpacityFormat2State ? "2_STATE" : "4_STATE", level,
                   format == format::kOpacityFormat2State ? "2" : "4", max);
}

}  // namespace

bool checkMicromapBuildInfoUsage(Validator& v, const VkMicromapBuildInfoEXT& info, const char* name) {
    const uint32_t before = v.failureCount();
    v.check(info.sType == VK_STRUCTURE_TYPE_MICROMAP_BUILD_INFO_EXT, "VUID-VkMicromapBuildInfoEXT-sType-sType",
            "%s.sType is %d.", name, int(info.sType));
    v.check(info.pNext == nullptr, "VUID-VkMicromapBuildInfoEXT-pNext-pNext", "%s.pNext is not NULL.", name);
    // DISPLACEMENT_MICROMAP_NV belongs to VK_NV_displacement_micromap, which vkas does not support.
    v.check(info.type == VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT, "VUID-VkMicromapBuildInfoEXT-type-parameter",
            "%s.type %d is not a VkMicromapTypeEXT of an enabled extension.", name, int(info.type));
    v.check((info.flags & ~kKnownBuildFlags) == 0, "VUID-VkMicromapBuildInfoEXT-flags-parameter",
            "%s.flags 0x%x has bits that are not VkBuildMicromapFlagBitsEXT.", name, info.flags);
    // Spec: "Only one of pUsageCounts or ppUsageCounts can be a valid pointer, the other must be NULL." With usage
    // counts to read, one of them is needed.
    const bool both = info.pUsageCounts != nullptr && info.ppUsageCounts != nullptr;
    const bool neither = info.pUsageCounts == nullptr && info.ppUsageCounts == nullptr && info.usageCountsCount != 0;
    if (!v.check(!both && !neither, "VUID-VkMicromapBuildInfoEXT-pUsageCounts-07516",
                 both ? "%s has both pUsageCounts and ppUsageCounts." : "%s has usageCountsCount %u but neither "
                                                                        "pUsageCounts nor ppUsageCounts.",
                 name, info.usageCountsCount))
        return false;
    for (uint32_t i = 0; i < info.usageCountsCount; ++i) {
        if (info.ppUsageCounts && !v.check(info.ppUsageCounts[i] != nullptr,
                                           "VUID-VkMicromapBuildInfoEXT-ppUsageCounts-parameter",
                                           "%s.ppUsageCounts[%u] is NULL.", name, i))
            continue;
        const VkMicromapUsageEXT& u = micromapUsage(info, i);
        if (info.type != VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT) continue;
        // Spec: "If type is VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT, for each member of pUsageCounts or ppUsageCounts,
        // format must be a valid value from VkOpacityMicromapFormatEXT"
        if (v.check(format::isOpacityFormat(u.format), "VUID-VkMicromapBuildInfoEXT-format-11652",
                    "%s usage count %u has format %u, not a VkOpacityMicromapFormatEXT.", name, i, u.format))
            // "... subdivisionLevel must be less than or equal to maxOpacity2StateSubdivisionLevel" (4-state alike)
            checkLevel(v, u.format, u.subdivisionLevel, "VUID-VkMicromapBuildInfoEXT-subdivisionLevel-11654",
                       "VUID-VkMicromapBuildInfoEXT-subdivisionLevel-11655", "usage count", name, i);
        if (v.failureCount() - before > 16) break;  // enough said
    }
    return v.failureCount() == before;
}

void checkBuildMicromaps(Validator& v, const Device& dev, VkDeferredOperationKHR deferredOperation,
                         uint32_t infoCount, const VkMicromapBuildInfoEXT* pInfos) {
    // vkBuildMicromapsEXT's valid usage does not include the deferred_operations_common rule (03678).
    if (deferredOperation != VK_NULL_HANDLE)
        checkHandle<DeferredOperation>(v, dev, deferredOperation, ObjectMagic::DeferredOperation,
                          "VUID-vkBuildMicromapsEXT-deferredOperation-parameter",
                          "VUID-vkBuildMicromapsEXT-deferredOperation-parent", "deferredOperation");
    v.check(infoCount > 0, "VUID-vkBuildMicromapsEXT-infoCount-arraylength", "infoCount is 0.");
    if (!v.check(pInfos != nullptr || infoCount == 0, "VUID-vkBuildMicromapsEXT-pInfos-parameter", "pInfos is NULL."))
        return;
    struct Written {
        uintptr_t begin;
        uint64_t size;
        uint32_t info;
    };
    HostVector<Written> written;
    for (uint32_t i = 0; i < infoCount; ++i) {
        const VkMicromapBuildInfoEXT& info = pInfos[i];
        char name[32];
        std::snprintf(name, sizeof name, "pInfos[%u]", i);
        const bool usageOk = checkMicromapBuildInfoUsage(v, info, name);
        // Spec: "The mode member of each element of pInfos must be a valid VkBuildMicromapModeEXT value"
        v.check(info.mode == VK_BUILD_MICROMAP_MODE_BUILD_EXT, "VUID-vkBuildMicromapsEXT-mode-07462",
                "%s.mode %d is not a VkBuildMicromapModeEXT.", name, int(info.mode));
        // Spec: "The dstMicromap member of any element of pInfos must be a valid VkMicromapEXT handle"
        const Micromap* dst = checkHandle<Micromap>(v, dev, info.dstMicromap, ObjectMagic::Micromap,
                                                    "VUID-vkBuildMicromapsEXT-dstMicromap-07463",
                                                    "VUID-vkBuildMicromapsEXT-dstMicromap-07463", "dstMicromap");
        if (dst) {
            // Unreachable: OPACITY_MICROMAP_EXT is the only type either may have (the type-parameter rules).
            if (info.type == VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT)
                v.check(info.type == dst->type, "VUID-vkBuildMicromapsEXT-pInfos-07464",
                    "%s.type %d is not the type %d %s.dstMicromap was created with.", name, int(info.type),
                    int(dst->type), name);
            v.check(dst->buffer->memory != nullptr, "VUID-vkBuildMicromapsEXT-pInfos-07552",
                    "the buffer of %s.dstMicromap is not bound to memory.", name);
        }
        if (!usageOk) continue;
        const uint64_t count = micromapTriangleCount(info);
        const uint64_t size = micromapSizeForUsage(info);
        if (dst)
            v.check(dst->size >= size, "VUID-vkBuildMicromapsEXT-pInfos-07461",
                    "%s.dstMicromap has size %llu but vkGetMicromapBuildSizesEXT gives micromapSize %llu for the "
                    "usage counts.",
                    name, (ull)dst->size, (ull)size);
        if (dst && dst->buffer->memory)
            written.push_back({reinterpret_cast<uintptr_t>(dst->block()), std::min<uint64_t>(size, dst->size), i});
        if (count == 0) continue;
        // Spec: "all referenced addresses of pInfos[i].data.hostAddress (triangleArray.hostAddress) must be valid
        // host memory": NULL never is.
        v.check(info.data.hostAddress != nullptr, "VUID-vkBuildMicromapsEXT-pInfos-07553",
                "%s has %llu triangles but data.hostAddress is NULL.", name, (ull)count);
        if (!v.check(info.triangleArray.hostAddress != nullptr, "VUID-vkBuildMicromapsEXT-pInfos-07554",
                     "%s has %llu triangles but triangleArray.hostAddress is NULL.", name, (ull)count) ||
            info.type != VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT)
            continue;
        Histogram usage, triangles;
        for (uint32_t k = 0; k < info.usageCountsCount; ++k) {
            const VkMicromapUsageEXT& u = micromapUsage(info, k);
            usage.count[Histogram::formatIndex(u.format)][u.subdivisionLevel] += u.count;
        }
        bool trianglesOk = true;
        for (uint64_t t = 0; t < count; ++t) {
            const format::MicromapTriangle tri = readMicromapTriangle(info, t);
            // Spec: "If type is VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT, for each member of triangleArray, format must
            // be a valid value from VkOpacityMicromapFormatEXT"
            if (!v.check(format::isOpacityFormat(tri.format), "VUID-VkMicromapBuildInfoEXT-format-11657",
                         "%s triangle %llu has format %u, not a VkOpacityMicromapFormatEXT.", name, (ull)t,
                         unsigned(tri.format)) ||
                !checkLevel(v, tri.format, tri.subdivisionLevel, "VUID-VkMicromapBuildInfoEXT-subdivisionLevel-11659",
                            "VUID-VkMicromapBuildInfoEXT-subdivisionLevel-11660", "triangle", name, t)) {
                trianglesOk = false;
                if (v.failureCount() > 16) return;  // enough said
                continue;
            }
            triangles.count[Histogram::formatIndex(tri.format)][tri.subdivisionLevel] += 1;
        }
        // The usage counts "describe the total counts used to build each micromap": triangles of other formats or
        // levels would not fit in the micromapSize the counts give, so a mismatch is reported with the size rule.
        if (trianglesOk)
            v.check(usage == triangles, "VUID-vkBuildMicromapsEXT-pInfos-07461",
                    "the formats and subdivision levels of %s's triangles do not match its usage counts, which "
                    "size the micromap.",
                    name);
    }
    // Spec: "The range of memory backing the dstMicromap member of any element of pInfos that is accessed by this
    // command must not overlap the memory backing the dstMicromap member of any other element of pInfos".
    std::sort(written.begin(), written.end(), [](const Written& a, const Written& b) { return a.begin < b.begin; });
    // Sorted by start, a range overlaps an earlier one exactly when it starts before the furthest end so far.
    for (size_t k = 1, furthest = 0; k < written.size(); ++k) {
        const Written& a = written[furthest];
        v.check(!rangesOverlap(a.begin, a.size, written[k].begin, written[k].size),
                "VUID-vkBuildMicromapsEXT-dstMicromap-11667",
                "the memory pInfos[%u] writes overlaps the memory pInfos[%u] writes.", written[k].info, a.info);
        if (written[k].begin + written[k].size > a.begin + a.size) furthest = k;
    }
}

}  // namespace vkas
