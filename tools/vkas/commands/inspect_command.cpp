#include "inspect_command.hpp"

#include <chrono>
#include <cstdio>
#include <memory>

#include "as_builder.hpp"
#include "build_preference.hpp"
#include "input_error.hpp"
#include "json_writer.hpp"
#include "model_loader.hpp"
#include "progress.hpp"
#include "structure_file.hpp"
#include "structure_tree.hpp"

namespace vkas_tool {
namespace {

// What is inspected, whichever the source.
struct Subject {
    bool serialized = false;
    ModelInfo model;                        // mesh input
    std::unique_ptr<StructureSet> built;    // mesh input
    VkBuildAccelerationStructureFlagsKHR flags = 0;
    std::unique_ptr<LoadedStructure> loaded;  // serialized input
    VkAccelerationStructureKHR handle = VK_NULL_HANDLE;
    const unsigned char* block = nullptr;
    size_t blockSize = 0;
};

// The file's meshes as one bottom level: each placed mesh a geometry whose transform is its node's.
void buildFromMesh(VkContext& ctx, const InspectOptions& o, Subject& s) {
    Scene scene;
    s.model = loadModel(o.file, scene);
    BlasDesc all;
    all.name = o.file;
    for (const InstanceDesc& inst : scene.instances) {
        GeometryDesc g = scene.blases.at(inst.blas).geometries.at(0);
        g.transform = inst.transform;
        all.geometries.push_back(g);
    }
    s.flags = preferenceFlags(o.preference) | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
    Progress::note("building " + o.file);
    s.built = buildBottomLevel(ctx, {all}, s.flags);
    if (ctx.validationMessages() != 0) throw std::runtime_error("the build reported: " + ctx.lastMessage());
    s.handle = s.built->handles[0];
    s.block = s.built->block(0);
    s.blockSize = static_cast<size_t>(s.built->stats[0].size);
}

std::string mib(uint64_t bytes) {
    char b[32];
    std::snprintf(b, sizeof b, "%.2f MiB", double(bytes) / 1048576.0);
    return b;
}

std::string share(uint64_t part, uint64_t whole) {
    char b[32];
    std::snprintf(b, sizeof b, "%.1f%%", whole ? 100.0 * double(part) / double(whole) : 0.0);
    return b;
}

void printHistogram(const char* title, const std::vector<uint64_t>& h, size_t first) {
    std::printf("%-14s", title);
    for (size_t i = first; i < h.size(); ++i)
        if (h[i]) std::printf(" %zu:%llu", i, static_cast<unsigned long long>(h[i]));
    std::printf("\n");
}

void printText(const InspectOptions& o, const Subject& s, const TreeStats& t, uint64_t compacted, uint64_t serialized) {
    if (s.serialized) {
        const SerializedHeader& h = s.loaded->header;
        std::printf("vkas inspect: %s (serialized structure, %llu bytes)\n", o.file.c_str(),
                    static_cast<unsigned long long>(s.loaded->fileSize));
        std::printf("%-14s layout %d: driverUUID \"%s\", compatibility UUID \"%s\"\n", "envelope", h.layout,
                    h.driverUuid.c_str(), h.compatibilityUuid.c_str());
        std::printf("%-14s serialized %llu bytes, deserialized %llu bytes, %llu bottom-level handles%s\n", "",
                    static_cast<unsigned long long>(h.serializedSize), static_cast<unsigned long long>(h.deserializedSize),
                    static_cast<unsigned long long>(h.handleCount), h.handleCount ? " (not loaded: instances inactive here)" : "");
        std::printf("%-14s passed: UUIDs compatible, sizes consistent, %s, tree and records valid "
                    "(vkCopyMemoryToAccelerationStructureKHR)\n",
                    "integrity", h.layout == 2 ? "XXH3-64 hash matches" : "no hash in layout 1");
    } else {
        std::printf("vkas inspect: %s (mesh: %u meshes, %u placed, %llu triangles, %llu vertices)\n", o.file.c_str(),
                    s.model.meshes, s.model.instances, static_cast<unsigned long long>(s.model.triangles),
                    static_cast<unsigned long long>(s.model.vertices));
        std::printf("%-14s %s in %.2f ms (one thread)\n", "built", buildFlagNames(s.flags).c_str(), s.built->buildMs);
    }
    std::printf("%-14s %s of %s, block format %u, build flags %s\n", "structure", structureTypeName(t.type),
                primitiveTypeName(t.primitiveType), t.version, buildFlagNames(t.buildFlags).c_str());
    std::printf("%-14s usedSize %llu, %u geometries, %u primitives, %u records, %u nodes\n", "header",
                static_cast<unsigned long long>(t.usedSize), t.geometryCount, t.primitiveCount, t.recordCount,
                t.nodeCount);
    std::printf("%-14s (%g, %g, %g) .. (%g, %g, %g)\n", "bounds", t.bounds[0], t.bounds[1], t.bounds[2], t.bounds[3],
                t.bounds[4], t.bounds[5]);
    if (!s.serialized)
        std::printf("%-14s size query %s (scratch %s), compacted %s (%s of it), serialized %s\n", "sizes",
                    mib(s.built->stats[0].size).c_str(), mib(s.built->stats[0].buildScratchSize).c_str(),
                    mib(compacted).c_str(), share(compacted, s.built->stats[0].size).c_str(), mib(serialized).c_str());
    else
        std::printf("%-14s compacted %s, serialized %s\n", "sizes", mib(compacted).c_str(), mib(serialized).c_str());
    std::printf("%-14s header %llu, geometries %llu, nodes %llu (%s), %s %llu (%s)", "bytes",
                static_cast<unsigned long long>(t.headerBytes), static_cast<unsigned long long>(t.geometryBytes),
                static_cast<unsigned long long>(t.nodeBytes), share(t.nodeBytes, t.usedSize).c_str(), t.recordPart(),
                static_cast<unsigned long long>(t.leafBytes + t.recordBytes + t.instanceBytes),
                share(t.leafBytes + t.recordBytes + t.instanceBytes, t.usedSize).c_str());
    if (t.micromapBytes) std::printf(", micromaps %llu", static_cast<unsigned long long>(t.micromapBytes));
    if (t.fragmentBytes) std::printf(", fragments %llu", static_cast<unsigned long long>(t.fragmentBytes));
    std::printf(", padding %llu\n", static_cast<unsigned long long>(t.paddingBytes));
    std::printf("%-14s %llu internal nodes, %llu leaves, %llu references; node fill %.3f; SAH cost %.2f\n", "tree",
                static_cast<unsigned long long>(t.internalNodes), static_cast<unsigned long long>(t.leaves),
                static_cast<unsigned long long>(t.references), t.nodeFill(), t.sahCost());
    printHistogram("leaf depth", t.leavesAtDepth, 0);
    printHistogram("leaf size", t.leafSizes, 1);
    printHistogram("children", std::vector<uint64_t>(t.childrenPerNode.begin(), t.childrenPerNode.end()), 1);
}

void printJson(const InspectOptions& o, const Subject& s, const TreeStats& t, uint64_t compacted, uint64_t serialized,
               uint64_t boxes) {
    JsonWriter j;
    j.beginObject().value("file", o.file).value("input", s.serialized ? "serialized" : "mesh");
    if (s.serialized) {
        const SerializedHeader& h = s.loaded->header;
        j.beginObject("serialized")
            .value("fileSize", s.loaded->fileSize)
            .value("layout", uint64_t(h.layout))
            .value("driverUUID", h.driverUuid)
            .value("compatibilityUUID", h.compatibilityUuid)
            .value("serializedSize", h.serializedSize)
            .value("deserializedSize", h.deserializedSize)
            .value("handleCount", h.handleCount)
            .value("integrity", "passed")
            .value("hashChecked", h.layout == 2)
            .end();
    } else {
        j.beginObject("mesh")
            .value("meshes", s.model.meshes)
            .value("instances", s.model.instances)
            .value("triangles", s.model.triangles)
            .value("vertices", s.model.vertices)
            .end();
        j.value("preference", o.preference).value("buildMs", s.built->buildMs);
    }
    j.beginObject("header")
        .value("version", t.version)
        .value("type", structureTypeName(t.type))
        .value("primitiveType", primitiveTypeName(t.primitiveType))
        .value("buildFlags", t.buildFlags)
        .value("buildFlagNames", buildFlagNames(t.buildFlags))
        .value("usedSize", t.usedSize)
        .value("geometryCount", t.geometryCount)
        .value("primitiveCount", t.primitiveCount)
        .value("recordCount", t.recordCount)
        .value("nodeCount", t.nodeCount)
        .value("geometryOffset", t.geometryOffset)
        .value("nodeOffset", t.nodeOffset)
        .value("recordOffset", t.recordOffset)
        .beginArray("boundsLower").value(nullptr, double(t.bounds[0])).value(nullptr, double(t.bounds[1])).value(nullptr, double(t.bounds[2])).end()
        .beginArray("boundsUpper").value(nullptr, double(t.bounds[3])).value(nullptr, double(t.bounds[4])).value(nullptr, double(t.bounds[5])).end()
        .end();
    j.beginObject("sizes");
    if (!s.serialized)
        j.value("accelerationStructureSize", uint64_t(s.built->stats[0].size))
            .value("buildScratchSize", uint64_t(s.built->stats[0].buildScratchSize));
    j.value("compacted", compacted).value("serialization", serialized).end();
    j.beginObject("bytes")
        .value("header", t.headerBytes)
        .value("geometries", t.geometryBytes)
        .value("nodes", t.nodeBytes)
        .value("leaves", t.leafBytes)
        .value("records", t.recordBytes)
        .value("instances", t.instanceBytes)
        .value("micromaps", t.micromapBytes)
        .value("fragments", t.fragmentBytes)
        .value("padding", t.paddingBytes)
        .end();
    j.beginObject("tree")
        .value("internalNodes", t.internalNodes)
        .value("leaves", t.leaves)
        .value("references", t.references)
        .value("nodeFill", t.nodeFill())
        .value("sahCost", t.sahCost())
        .array("nodesAtDepth", t.nodesAtDepth)
        .array("leavesAtDepth", t.leavesAtDepth)
        .array("leafSizes", t.leafSizes)
        .array("childrenPerNode", std::vector<uint64_t>(t.childrenPerNode.begin(), t.childrenPerNode.end()))
        .end();
    if (o.boxesLevel >= 0)
        j.beginObject("boxes").value("level", uint64_t(o.boxesLevel)).value("count", boxes).value("file", o.boxesFile).end();
    if (!o.writeBlob.empty()) j.value("wroteBlob", o.writeBlob);
    j.end();
    std::printf("%s\n", j.str().c_str());
}

}  // namespace

int runInspect(const InspectOptions& o) {
    DeviceOptions deviceOptions;
    deviceOptions.validation = o.validation;
    deviceOptions.collectMessages = true;  // a refused blob's message becomes part of ours
    VkContext ctx(deviceOptions);

    Subject s;
    if (looksSerialized(o.file)) {
        Progress::note("loading " + o.file);
        s.serialized = true;
        s.loaded = std::make_unique<LoadedStructure>(loadSerialized(ctx, o.file));
        s.handle = s.loaded->handle;
        s.block = s.loaded->block();
        s.blockSize = s.loaded->blockSize();
    } else {
        buildFromMesh(ctx, o, s);
    }
    const TreeStats t = analyseTree(s.block, s.blockSize);
    // COMPACTED_SIZE needs ALLOW_COMPACTION (VUID 03431); SIZE_KHR is the same number for any structure in vkas.
    const uint64_t compacted = queryStructureProperty(
        ctx, s.handle, (t.buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR)
                           ? VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR
                           : VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR);
    const uint64_t serialized =
        queryStructureProperty(ctx, s.handle, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR);

    uint64_t boxCount = 0;
    if (o.boxesLevel >= 0) {
        const std::vector<Box> boxes = boxesAtLevel(s.block, s.blockSize, static_cast<uint32_t>(o.boxesLevel));
        boxCount = boxes.size();
        writeBoxesObj(o.boxesFile, boxes,
                      "vkas inspect " + o.file + ": the boxes of tree level " + std::to_string(o.boxesLevel));
    }
    if (!o.writeBlob.empty()) writeSerialized(ctx, s.handle, o.writeBlob);
    Progress::clear();
    if (o.json) printJson(o, s, t, compacted, serialized, boxCount);
    else {
        printText(o, s, t, compacted, serialized);
        if (o.boxesLevel >= 0)
            std::printf("%-14s %llu boxes of level %lld written to %s\n", "boxes",
                        static_cast<unsigned long long>(boxCount), static_cast<long long>(o.boxesLevel),
                        o.boxesFile.c_str());
        if (!o.writeBlob.empty()) std::printf("%-14s serialized to %s\n", "blob", o.writeBlob.c_str());
    }
    return 0;
}

}  // namespace vkas_tool
