// libFuzzer target: the input is a serialized acceleration structure (docs/FORMAT.md, "Serialized form") given to
// vkGetDeviceAccelerationStructureCompatibilityKHR and vkCopyMemoryToAccelerationStructureKHR, on a device with
// validation on and on one with validation off. Serialized data is always checked: whatever the bytes, the command
// must either load them or reject them with an error, writing nothing, reading nothing outside the blob. What it
// accepts is traced (ray queries, batch traces), cloned, serialized again and loaded again (byte-identical).
//
// Handle-array entries 1 to 13 are tokens the harness replaces by structures of the device (fuzz_common.hpp builds
// them): 1 a triangle bottom level, 2 its device address, 3 AABBs, 4 spheres, 5 LSS, 6 a top level, 7 the
// destination itself, 8 a structure never built, 9 a destroyed handle, 10 a structure of the other device, 11 the
// AABB structure's address, 12 a motion-triangle bottom level, 13 a motion top level. Other values stay as they are
// (garbage, to be rejected or made inactive).
#include <algorithm>
#include <cstring>

#include "engine/format/check.hpp"  // the hash is resealed the way vkas checks it
#include "engine/format/serialize.hpp"
#include "fuzz_common.hpp"

namespace {

using fz::Device;
using fz::Region;
using fz::Structure;

// The largest blob the harness allocates (scripts/run-fuzzers.sh gives inputs of at most 16 KiB; a larger claimed
// serialized size is replaced by the input size).
constexpr uint64_t kMaxExtent = 1u << 16;
// The driver UUIDs of serialized layouts 1 and 2 (docs/FORMAT.md), written out here as the format document gives them.
constexpr uint8_t kDriverUuid[16] = {'V', 'K', 'A', 'S', '-', 'D', 'R', 'I', 'V', 'E', 'R', '-', 'F', 'M', 'T', '1'};
constexpr uint8_t kDriverUuid2[16] = {'V', 'K', 'A', 'S', '-', 'S', 'E', 'R', 'I', 'A', 'L', 'I', 'Z', 'E', 'D', '2'};
// The compatibility UUIDs of block formats 1 and 2: layout 1 carries format 1 only, layout 2 either.
constexpr uint8_t kCompatUuid[16] = {'V', 'K', 'A', 'S', '-', 'A', 'S', '-', 'F', 'O', 'R', 'M', 'A', 'T', '-', '1'};
constexpr uint8_t kCompatUuid2[16] = {'V', 'K', 'A', 'S', '-', 'A', 'S', '-', 'F', 'O', 'R', 'M', 'A', 'T', '-', '2'};

uint64_t load64(const uint8_t* p) {
    uint64_t v;
    std::memcpy(&v, p, 8);
    return v;
}
uint32_t load32(const uint8_t* p) {
    uint32_t v;
    std::memcpy(&v, p, 4);
    return v;
}
void store64(uint8_t* p, uint64_t v) { std::memcpy(p, &v, 8); }

// Whether the n bytes at p all equal `value`. memcmp of the range with itself shifted by one byte: no per-byte loop
// (with coverage instrumentation a byte loop over a destination costs more than the whole load).
bool allBytes(const uint8_t* p, size_t n, uint8_t value) {
    return n == 0 || (p[0] == value && std::memcmp(p, p + 1, n - 1) == 0);
}

// The blob as the application hands it over: 16-byte aligned, readable up to its header's serialized size (the
// extent the command may read). A serialized size beyond what the harness allocates is replaced by the input size.
Region makeBlob(const uint8_t* data, size_t size) {
    uint64_t extent = std::max<uint64_t>(size, 56);
    if (size >= 40) {
        const uint64_t claimed = load64(data + 32);
        if (claimed > extent && claimed <= kMaxExtent) extent = claimed;
    }
    Region blob(extent, 0);
    std::memcpy(blob.data, data, size);
    if (load64(blob.data + 32) > extent) store64(blob.data + 32, extent);
    return blob;
}

uint64_t tokenValue(Device& d, Device& other, const Structure& dst, uint64_t token) {
    switch (token) {
        case 1: return uint64_t(d.blasTriangles.handle);
        case 2: return d.address(d.blasTriangles);
        case 3: return uint64_t(d.blasAabbs.handle);
        case 4: return uint64_t(d.blasSpheres.handle);
        case 5: return uint64_t(d.blasLss.handle);
        case 6: return uint64_t(d.tlas.handle);
        case 7: return uint64_t(dst.handle);
        case 8: return uint64_t(d.unbuilt.handle);
        case 9: return d.deadHandle;
        case 10: return uint64_t(other.blasTriangles.handle);
        case 11: return d.address(d.blasAabbs);
        case 12: return uint64_t(d.blasMotion.handle);
        case 13: return uint64_t(d.tlasMotion.handle);
        default: return token;
    }
}

void replaceTokens(Device& d, Device& other, const Structure& dst, Region& blob) {
    const uint64_t n = load64(blob.data + 48);
    for (uint64_t k = 0; k < n && 56 + 8 * (k + 1) <= blob.size; ++k) {
        uint8_t* p = blob.data + 56 + 8 * k;
        const uint64_t v = load64(p);
        if (v >= 1 && v <= 13) store64(p, tokenValue(d, other, dst, v));
    }
}

VkResult deserialize(Device& d, const Structure& dst, const void* blob, bool deferred) {
    VkCopyMemoryToAccelerationStructureInfoKHR ci{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
    ci.src.hostAddress = blob;
    ci.dst = dst.handle;
    ci.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    if (!deferred) return d.vkCopyMemoryToAccelerationStructureKHR(d.device, VK_NULL_HANDLE, &ci);
    VkDeferredOperationKHR op;
    FZ_CHECK(d.vkCreateDeferredOperationKHR(d.device, nullptr, &op) == VK_SUCCESS, "vkCreateDeferredOperationKHR");
    VkResult r = d.vkCopyMemoryToAccelerationStructureKHR(d.device, op, &ci);
    if (r == VK_OPERATION_DEFERRED_KHR) {
        VkResult j;
        int rounds = 0;
        while ((j = d.vkDeferredOperationJoinKHR(d.device, op)) == VK_THREAD_IDLE_KHR)
            FZ_CHECK(++rounds < 1000000, "a deferred deserialization never completes");
        FZ_CHECK(j == VK_SUCCESS || j == VK_THREAD_DONE_KHR, "vkDeferredOperationJoinKHR returned %d", int(j));
        r = d.vkGetDeferredOperationResultKHR(d.device, op);
        FZ_CHECK(r != VK_NOT_READY, "the operation is still pending after its only thread joined it");
    }
    d.vkDestroyDeferredOperationKHR(d.device, op, nullptr);
    return r;
}

// Everything done with a structure the command loaded: traces, a clone, serialization and a second load.
void exercise(Device& d, Structure& dst, uint64_t deserializedSize, uint64_t serializedSize, bool format1,
              const uint8_t* seed, size_t seedSize) {
    const uint8_t* block = dst.block();
    // A block of format 2 loads as it is; one of format 1 is rewritten as format 2, which only shrinks it
    // (docs/FORMAT.md, "Format 1"). Either way the loaded structure is format 2 and nothing past it is written.
    const uint64_t loaded = d.usedSize(dst);
    FZ_CHECK(format1 ? loaded <= deserializedSize : loaded == deserializedSize, "usedSize %llu after loading %llu bytes%s",
             (unsigned long long)loaded, (unsigned long long)deserializedSize, format1 ? " of format 1" : "");
    FZ_CHECK(load32(block + 4) == 2, "a loaded structure of format version %u", load32(block + 4));
    FZ_CHECK(allBytes(block + loaded, dst.buffer.size - dst.offset - loaded, 0xAA),
             "the load wrote past the loaded structure");
    serializedSize -= deserializedSize - loaded;  // vkas serializes the loaded (format-2) block
    deserializedSize = loaded;
    const uint32_t type = load32(block + 8);
    float bounds[6];
    std::memcpy(bounds, block + 32, sizeof bounds);
    if (type == 0) {
        fz::traceProbe(d, dst.handle, bounds, seed, seedSize);
    } else {
        // A bottom level built with motion goes into a motion top level (an instance type the seed chooses); others
        // now and then too.
        const uint8_t pick = seedSize > 1 ? seed[1] : 0;
        const int motionType = (fz::builtWithMotion(block) || (pick & 4)) ? int(pick % 3) : -1;
        Structure top = d.buildSingleInstanceTlas(dst, seedSize ? seed[0] : 0, motionType);
        fz::traceProbe(d, top.handle, bounds, seed, seedSize);
        d.destroyStructure(top);
    }

    // A clone is the same bytes.
    const VkAccelerationStructureTypeKHR loadedType =
        type == 0 ? VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR : VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    Structure clone = d.createStructure(loadedType, (deserializedSize + 255) / 256 * 256);
    VkCopyAccelerationStructureInfoKHR cc{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
    cc.src = dst.handle;
    cc.dst = clone.handle;
    cc.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR;
    FZ_CHECK(d.vkCopyAccelerationStructureKHR(d.device, VK_NULL_HANDLE, &cc) == VK_SUCCESS, "clone of a loaded structure");
    FZ_CHECK(std::memcmp(clone.block(), block, deserializedSize) == 0, "the clone differs from its source");

    // Serialize, load again: the same serialized size and the same block.
    VkDeviceSize size = 0;
    FZ_CHECK(d.vkWriteAccelerationStructuresPropertiesKHR(d.device, 1, &dst.handle,
                                                          VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR,
                                                          sizeof size, &size, sizeof size) == VK_SUCCESS,
             "SERIALIZATION_SIZE query");
    FZ_CHECK(size == serializedSize, "serialization size %llu, loaded from a blob of %llu", (unsigned long long)size,
             (unsigned long long)serializedSize);
    Region out(size, 0xAA);
    VkCopyAccelerationStructureToMemoryInfoKHR sc{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
    sc.src = dst.handle;
    sc.dst.hostAddress = out.data;
    sc.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
    FZ_CHECK(d.vkCopyAccelerationStructureToMemoryKHR(d.device, VK_NULL_HANDLE, &sc) == VK_SUCCESS,
             "serialization of a loaded structure");
    Structure again = d.createStructure(loadedType, (deserializedSize + 255) / 256 * 256);
    const uint64_t before = d.messages();
    FZ_CHECK(deserialize(d, again, out.data, false) == VK_SUCCESS, "vkas rejects what it serialized itself");
    FZ_CHECK(d.messages() == before, "validation reported loading what vkas serialized");
    FZ_CHECK(std::memcmp(again.block(), block, deserializedSize) == 0, "serialize + load changed the structure");
    d.destroyStructure(again);
    d.destroyStructure(clone);
}

// Loads the blob on one device; returns the result of vkCopyMemoryToAccelerationStructureKHR.
VkResult runOn(Device& d, Device& other, const uint8_t* data, size_t size, bool compatible) {
    Region blob = makeBlob(data, size);
    const uint64_t h = fz::hashBytes(data, size);
    // The destination has the claimed deserialized size, but at most the blob's extent (rounded up, plus 256): a load
    // copies its structure out of the blob, so a larger destination only costs time (most fuzzed claims are huge).
    const uint64_t claimedDeserialized = load64(blob.data + 40);
    const uint64_t dstLimit = (blob.size + 255) / 256 * 256 + 256;
    const uint64_t dstSize =
        std::clamp<uint64_t>((std::min<uint64_t>(claimedDeserialized, kMaxExtent) + 255) / 256 * 256, 256, dstLimit);
    // The type the blob's block names (top level 0); now and then a GENERIC destination.
    uint32_t blockType = 1;
    const uint64_t n = load64(blob.data + 48);
    // Serialized layout 2 puts the 8-byte integrity hash between the handle array and the block.
    const uint64_t blockAt = 56 + 8 * n + (std::memcmp(blob.data, vkas::serial::kDriverUuidV2, 16) == 0 ? 8 : 0);
    if (n < kMaxExtent / 8 && blockAt + 12 <= blob.size) blockType = load32(blob.data + blockAt + 8);
    VkAccelerationStructureTypeKHR type = blockType == 0 ? VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR
                                                         : VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    if ((h & 7) == 5) type = VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR;
    Structure dst = d.createStructure(type, dstSize);
    replaceTokens(d, other, dst, blob);
    // Most mutated inputs no longer match their integrity hash: reseal seven in eight of them, so that the fuzzer
    // reaches the structural checks behind the hash (and the eighth keeps testing the hash itself).
    if ((h >> 3 & 7) != 0) {
        vkas::serial::SerializedView view;
        if (vkas::format::checkSerializedLayout(reinterpret_cast<const std::byte*>(blob.data), blob.size, &view).ok())
            vkas::serial::sealIntegrityHash(view, reinterpret_cast<std::byte*>(blob.data));
    }

    // The compatibility query reads the two UUIDs.
    VkAccelerationStructureVersionInfoKHR vi{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_VERSION_INFO_KHR};
    vi.pVersionData = blob.data;
    VkAccelerationStructureCompatibilityKHR compat = VK_ACCELERATION_STRUCTURE_COMPATIBILITY_MAX_ENUM_KHR;
    d.vkGetDeviceAccelerationStructureCompatibilityKHR(d.device, &vi, &compat);
    FZ_CHECK(compat == (compatible ? VK_ACCELERATION_STRUCTURE_COMPATIBILITY_COMPATIBLE_KHR
                                   : VK_ACCELERATION_STRUCTURE_COMPATIBILITY_INCOMPATIBLE_KHR),
             "compatibility %d for UUIDs that are %s", int(compat), compatible ? "vkas's" : "not vkas's");

    Region copy(blob.size);
    std::memcpy(copy.data, blob.data, blob.size);
    const uint64_t before = d.messages();
    const VkResult r = deserialize(d, dst, blob.data, (h & 3) == 1);
    const uint64_t reported = d.messages() - before;
    if (std::getenv("VKAS_FUZZ_VERBOSE"))
        std::fprintf(stderr, "vkas fuzz: the load (validation %s) returned %d after %llu validation message(s)\n",
                     d.validation ? "on" : "off", int(r), (unsigned long long)reported);
    FZ_CHECK(std::memcmp(copy.data, blob.data, blob.size) == 0, "the load wrote into the serialized data");
    if (d.validation) {
        FZ_CHECK(r == VK_SUCCESS || r == VK_ERROR_VALIDATION_FAILED_EXT || r == VK_ERROR_INCOMPATIBLE_VERSION_KHR,
                 "result %d with validation on", int(r));
        FZ_CHECK((r == VK_SUCCESS) == (reported == 0), "result %d with %llu validation message(s)", int(r),
                 (unsigned long long)reported);
    } else {
        FZ_CHECK(r == VK_SUCCESS || r == VK_ERROR_UNKNOWN || r == VK_ERROR_INCOMPATIBLE_VERSION_KHR,
                 "result %d with validation off", int(r));
        FZ_CHECK(reported == 0, "messages with validation off");
    }
    FZ_CHECK((r == VK_ERROR_INCOMPATIBLE_VERSION_KHR) == !compatible, "result %d for %s UUIDs", int(r),
             compatible ? "compatible" : "incompatible");
    if (r != VK_SUCCESS) {
        FZ_CHECK(allBytes(dst.buffer.data, dst.buffer.size, 0xAA), "a rejected load (result %d) wrote to its destination",
                 int(r));
    } else {
        const size_t seedOff = std::min<size_t>(size, 56);
        // vkas writes serialized layout 2: a loaded layout-1 blob serializes 8 bytes (the integrity hash) larger.
        const bool layout1 = std::memcmp(blob.data, vkas::serial::kDriverUuidV1, 16) == 0;
        // The compatibility UUID names the block's format version (docs/FORMAT.md).
        const bool format1 = std::memcmp(blob.data + 16, vkas::serial::kCompatibilityUuidV1, 16) == 0;
        exercise(d, dst, load64(blob.data + 40), load64(blob.data + 32) + (layout1 ? 8 : 0), format1, data + seedOff,
                 std::min<size_t>(size - seedOff, 128));
    }
    d.destroyStructure(dst);
    return r;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size > kMaxExtent) return 0;
    Device& on = fz::validatingDevice();
    Device& off = fz::plainDevice();
    const bool format1 = size >= 32 && std::memcmp(data + 16, kCompatUuid, 16) == 0;
    const bool format2 = size >= 32 && std::memcmp(data + 16, kCompatUuid2, 16) == 0;
    const bool compatible = (size >= 32 && std::memcmp(data, kDriverUuid, 16) == 0 && format1) ||
                            (size >= 32 && std::memcmp(data, kDriverUuid2, 16) == 0 && (format1 || format2));
    const VkResult rOn = runOn(on, off, data, size, compatible);
    const VkResult rOff = runOn(off, on, data, size, compatible);
    // Validation adds checks of the handles only: what it accepts loads without it too.
    FZ_CHECK(rOn != VK_SUCCESS || rOff == VK_SUCCESS, "accepted with validation on (%d) but not off (%d)", int(rOn),
             int(rOff));
    return 0;
}
