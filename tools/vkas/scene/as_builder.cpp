#include "as_builder.hpp"

#include <chrono>
#include <deque>
#include <cstring>

namespace vkas_tool {
namespace {

constexpr VkDeviceSize kStructureAlignment = 256;  // VkAccelerationStructureCreateInfoKHR::offset rule

VkDeviceSize alignUp(VkDeviceSize v, VkDeviceSize a) { return (v + a - 1) / a * a; }

double millisecondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// IEEE binary16 from binary32, round to nearest even.
uint16_t floatToHalf(float f) {
    uint32_t x;
    std::memcpy(&x, &f, 4);
    uint32_t sign = (x >> 16) & 0x8000u, mant = x & 0x7FFFFFu;
    int32_t biased = static_cast<int32_t>((x >> 23) & 0xFFu);
    if (biased == 0xFF) return static_cast<uint16_t>(sign | 0x7C00u | (mant ? 0x200u : 0u));
    int32_t exp = biased - 127 + 15;
    if (exp >= 31) return static_cast<uint16_t>(sign | 0x7C00u);
    if (exp <= 0) {
        if (exp < -10) return static_cast<uint16_t>(sign);
        mant |= 0x800000u;
        uint32_t shift = static_cast<uint32_t>(14 - exp), h = mant >> shift, rem = mant & ((1u << shift) - 1);
        uint32_t half = 1u << (shift - 1);
        if (rem > half || (rem == half && (h & 1u))) ++h;
        return static_cast<uint16_t>(sign | h);
    }
    uint32_t h = (static_cast<uint32_t>(exp) << 10) | (mant >> 13), rem = mant & 0x1FFFu;
    if (rem > 0x1000u || (rem == 0x1000u && (h & 1u))) ++h;  // a carry correctly rounds up into the exponent
    return static_cast<uint16_t>(sign | h);
}

// Appends bytes at aligned offsets; the result is copied into a HostBuffer once it is complete.
class ByteWriter {
public:
    VkDeviceSize append(const void* data, size_t size, size_t alignment) {
        size_t offset = static_cast<size_t>(alignUp(bytes_.size(), alignment));
        bytes_.resize(offset + size);
        std::memcpy(bytes_.data() + offset, data, size);
        return offset;
    }
    template <typename T>
    VkDeviceSize append(const std::vector<T>& v, size_t alignment) {
        return append(v.data(), v.size() * sizeof(T), alignment);
    }
    const std::vector<unsigned char>& bytes() const { return bytes_; }

private:
    std::vector<unsigned char> bytes_;
};

struct VertexEncoding {
    VkFormat format;
    VkDeviceSize stride;
    VkDeviceSize componentSize;
};

VertexEncoding encodingOf(VertexLayout layout) {
    switch (layout) {
    case VertexLayout::Float3: return {VK_FORMAT_R32G32B32_SFLOAT, 12, 4};
    case VertexLayout::Float3Interleaved: return {VK_FORMAT_R32G32B32_SFLOAT, 24, 4};
    case VertexLayout::Float4: return {VK_FORMAT_R32G32B32A32_SFLOAT, 16, 4};
    case VertexLayout::Half4: return {VK_FORMAT_R16G16B16A16_SFLOAT, 8, 2};
    }
    return {VK_FORMAT_R32G32B32_SFLOAT, 12, 4};
}

std::vector<unsigned char> encodeVertices(const Mesh& mesh, VertexLayout layout) {
    std::vector<unsigned char> out;
    VertexEncoding enc = encodingOf(layout);
    out.resize(mesh.positions.size() * enc.stride);
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        unsigned char* dst = out.data() + i * enc.stride;
        const Vec3& p = mesh.positions[i];
        switch (layout) {
        case VertexLayout::Float3: {
            float v[3] = {p.x, p.y, p.z};
            std::memcpy(dst, v, 12);
            break;
        }
        case VertexLayout::Float3Interleaved: {
            const Vec3 n = mesh.normals.empty() ? Vec3{} : mesh.normals[i];
            float v[6] = {p.x, p.y, p.z, n.x, n.y, n.z};
            std::memcpy(dst, v, 24);
            break;
        }
        case VertexLayout::Float4: {
            float v[4] = {p.x, p.y, p.z, 1.0f};
            std::memcpy(dst, v, 16);
            break;
        }
        case VertexLayout::Half4: {
            uint16_t v[4] = {floatToHalf(p.x), floatToHalf(p.y), floatToHalf(p.z), floatToHalf(1.0f)};
            std::memcpy(dst, v, 8);
            break;
        }
        }
    }
    return out;
}

// Where the data of a sphere, swept-sphere or box structure sits in the input buffer.
struct PrimitivePlacement {
    VkDeviceSize positions = 0, radii = 0, indices = 0, boxes = 0;
    uint32_t vertexCount = 0, primitiveCount = 0;
};

PrimitivePlacement placePrimitives(ByteWriter& writer, const BlasDesc& blas) {
    PrimitivePlacement p;
    std::vector<float> positions, radii;
    auto addPoint = [&](Vec3 v, float r) {
        positions.insert(positions.end(), {v.x, v.y, v.z});
        radii.push_back(r);
    };
    switch (blas.kind) {
    case PrimitiveKind::Triangles: break;
    case PrimitiveKind::Spheres:
        for (const Sphere& sp : blas.spheres) addPoint(sp.center, sp.radius);
        p.primitiveCount = static_cast<uint32_t>(blas.spheres.size());
        break;
    case PrimitiveKind::SweptSpheres: {
        // SUCCESSIVE indexing: index k makes the segment (k, k + 1), so a chain of n points contributes the
        // indices of its first n - 1 points.
        std::vector<uint32_t> indices;
        for (const SweptSphereChain& c : blas.chains) {
            const uint32_t first = static_cast<uint32_t>(radii.size());
            for (size_t k = 0; k < c.points.size(); ++k) addPoint(c.points[k], c.radii[k]);
            for (uint32_t k = 0; k < c.segmentCount(); ++k) indices.push_back(first + k);
        }
        p.indices = writer.append(indices, 4);
        p.primitiveCount = static_cast<uint32_t>(indices.size());
        break;
    }
    case PrimitiveKind::ProceduralBoxes: {
        std::vector<VkAabbPositionsKHR> boxes;
        for (const Box& bx : blas.boxes) boxes.push_back({bx.lo.x, bx.lo.y, bx.lo.z, bx.hi.x, bx.hi.y, bx.hi.z});
        p.boxes = writer.append(boxes, 8);
        p.primitiveCount = static_cast<uint32_t>(boxes.size());
        return p;
    }
    }
    p.vertexCount = static_cast<uint32_t>(radii.size());
    p.positions = writer.append(positions, 4);
    p.radii = writer.append(radii, 4);
    return p;
}

// The pNext data of one sphere or swept-sphere geometry.
struct PrimitiveData {
    VkAccelerationStructureGeometrySpheresDataNV spheres{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV};
    VkAccelerationStructureGeometryLinearSweptSpheresDataNV lss{
        VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_LINEAR_SWEPT_SPHERES_DATA_NV};
};

VkAccelerationStructureGeometryKHR primitiveGeometry(const BlasDesc& blas, const PrimitivePlacement& p,
                                                     const unsigned char* base, PrimitiveData& data,
                                                     VkAccelerationStructureBuildRangeInfoKHR& range) {
    VkAccelerationStructureGeometryKHR geom{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    geom.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
    range.primitiveCount = p.primitiveCount;
    switch (blas.kind) {
    case PrimitiveKind::Triangles: break;
    case PrimitiveKind::Spheres: {
        auto& s = data.spheres;
        s.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        s.vertexData.hostAddress = base + p.positions;
        s.vertexStride = 12;
        s.radiusFormat = VK_FORMAT_R32_SFLOAT;
        s.radiusData.hostAddress = base + p.radii;
        s.radiusStride = 4;
        s.indexType = VK_INDEX_TYPE_NONE_KHR;  // sphere i is entry i
        geom.geometryType = VK_GEOMETRY_TYPE_SPHERES_NV;
        geom.pNext = &s;
        break;
    }
    case PrimitiveKind::SweptSpheres: {
        auto& l = data.lss;
        l.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        l.vertexData.hostAddress = base + p.positions;
        l.vertexStride = 12;
        l.radiusFormat = VK_FORMAT_R32_SFLOAT;
        l.radiusData.hostAddress = base + p.radii;
        l.radiusStride = 4;
        l.indexType = VK_INDEX_TYPE_UINT32;
        l.indexData.hostAddress = base + p.indices;
        l.indexStride = 4;
        l.indexingMode = VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV;
        l.endCapsMode = VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_CHAINED_NV;
        geom.geometryType = VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV;
        geom.pNext = &l;
        break;
    }
    case PrimitiveKind::ProceduralBoxes: {
        auto& a = geom.geometry.aabbs;
        a.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
        a.data.hostAddress = base + p.boxes;
        a.stride = sizeof(VkAabbPositionsKHR);
        geom.geometryType = VK_GEOMETRY_TYPE_AABBS_KHR;
        break;
    }
    }
    return geom;
}

}  // namespace

HostBuffer::HostBuffer(VkContext& ctx, VkDeviceSize size, VkBufferUsageFlags usage) : ctx_(ctx), size_(size) {
    VkDevice dev = ctx.device();
    VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bci.size = size > 0 ? size : 1;
    bci.usage = usage | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
    bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    check(ctx.vkCreateBuffer(dev, &bci, nullptr, &buffer_), "vkCreateBuffer");
    try {
        VkMemoryRequirements req{};
        ctx.vkGetBufferMemoryRequirements(dev, buffer_, &req);
        if (!(req.memoryTypeBits & 1u))
            throw VkError("vkGetBufferMemoryRequirements: memory type 0 not allowed", VK_ERROR_UNKNOWN);
        VkMemoryAllocateFlagsInfo flagsInfo{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
        flagsInfo.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
        VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, &flagsInfo};
        mai.allocationSize = req.size;
        mai.memoryTypeIndex = 0;  // vkas: the one host-visible, host-coherent, device-local type
        check(ctx.vkAllocateMemory(dev, &mai, nullptr, &memory_), "vkAllocateMemory");
        check(ctx.vkBindBufferMemory(dev, buffer_, memory_, 0), "vkBindBufferMemory");
        check(ctx.vkMapMemory(dev, memory_, 0, VK_WHOLE_SIZE, 0, &mapped_), "vkMapMemory");
        VkBufferDeviceAddressInfo bai{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        bai.buffer = buffer_;
        address_ = ctx.vkGetBufferDeviceAddress(dev, &bai);
    } catch (...) {
        if (memory_) ctx.vkFreeMemory(dev, memory_, nullptr);
        ctx.vkDestroyBuffer(dev, buffer_, nullptr);
        throw;
    }
}

HostBuffer::~HostBuffer() {
    VkDevice dev = ctx_.device();
    if (mapped_) ctx_.vkUnmapMemory(dev, memory_);
    ctx_.vkDestroyBuffer(dev, buffer_, nullptr);
    ctx_.vkFreeMemory(dev, memory_, nullptr);
}

StructureSet::~StructureSet() {
    for (VkAccelerationStructureKHR h : handles) ctx_.vkDestroyAccelerationStructureKHR(ctx_.device(), h, nullptr);
}

uint64_t StructureSet::totalPrimitives() const {
    uint64_t n = 0;
    for (const StructureStats& s : stats) n += s.primitives;
    return n;
}

VkDeviceSize StructureSet::totalSize() const {
    VkDeviceSize n = 0;
    for (const StructureStats& s : stats) n += s.size;
    return n;
}

VkBuildAccelerationStructureFlagsKHR defaultBuildFlags() {
    return VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR;
}

namespace {

// Everything the build of several structures of one level needs once the per-structure inputs are filled in:
// sizes query, storage and scratch buffers, creation, one build call.
void createAndBuild(VkContext& ctx, StructureSet& set, VkAccelerationStructureTypeKHR type,
                    std::vector<VkAccelerationStructureBuildGeometryInfoKHR>& infos,
                    const std::vector<std::vector<uint32_t>>& maxPrimitiveCounts,
                    const std::vector<std::vector<VkAccelerationStructureBuildRangeInfoKHR>>& ranges) {
    VkDevice dev = ctx.device();
    VkPhysicalDeviceAccelerationStructurePropertiesKHR props{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_PROPERTIES_KHR};
    vkasGetAccelerationStructureProperties(dev, &props);
    const VkDeviceSize scratchAlign = props.minAccelerationStructureScratchOffsetAlignment
                                          ? props.minAccelerationStructureScratchOffsetAlignment
                                          : 1;

    auto t0 = std::chrono::steady_clock::now();
    std::vector<VkAccelerationStructureBuildSizesInfoKHR> sizes(infos.size());
    std::vector<VkDeviceSize> storageOffsets(infos.size()), scratchOffsets(infos.size());
    VkDeviceSize storageTotal = 0, scratchTotal = 0;
    for (size_t i = 0; i < infos.size(); ++i) {
        sizes[i].sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR;
        ctx.vkGetAccelerationStructureBuildSizesKHR(dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &infos[i],
                                                    maxPrimitiveCounts[i].data(), &sizes[i]);
        storageOffsets[i] = storageTotal;
        storageTotal = alignUp(storageTotal + sizes[i].accelerationStructureSize, kStructureAlignment);
        scratchOffsets[i] = scratchTotal;
        scratchTotal = alignUp(scratchTotal + sizes[i].buildScratchSize, scratchAlign);
        set.stats[i].size = sizes[i].accelerationStructureSize;
        set.stats[i].buildScratchSize = sizes[i].buildScratchSize;
    }
    set.sizeQueryMs = millisecondsSince(t0);

    set.storage = std::make_unique<HostBuffer>(ctx, storageTotal, VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR);
    HostBuffer scratch(ctx, scratchTotal, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
    set.scratchBytes = scratchTotal;

    std::vector<const VkAccelerationStructureBuildRangeInfoKHR*> rangePointers;
    for (size_t i = 0; i < infos.size(); ++i) {
        VkAccelerationStructureCreateInfoKHR aci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
        aci.buffer = set.storage->buffer();
        aci.offset = storageOffsets[i];
        aci.size = sizes[i].accelerationStructureSize;
        aci.type = type;
        VkAccelerationStructureKHR handle = VK_NULL_HANDLE;
        check(ctx.vkCreateAccelerationStructureKHR(dev, &aci, nullptr, &handle), "vkCreateAccelerationStructureKHR");
        set.handles.push_back(handle);
        set.offsets.push_back(storageOffsets[i]);
        infos[i].dstAccelerationStructure = handle;
        infos[i].scratchData.hostAddress = scratch.data() + scratchOffsets[i];
        rangePointers.push_back(ranges[i].data());
    }

    t0 = std::chrono::steady_clock::now();
    check(ctx.vkBuildAccelerationStructuresKHR(dev, VK_NULL_HANDLE, static_cast<uint32_t>(infos.size()), infos.data(),
                                               rangePointers.data()),
          "vkBuildAccelerationStructuresKHR");
    set.buildMs = millisecondsSince(t0);
}

}  // namespace

std::unique_ptr<StructureSet> buildBottomLevel(VkContext& ctx, const std::vector<BlasDesc>& blases,
                                               VkBuildAccelerationStructureFlagsKHR flags) {
    auto set = std::make_unique<StructureSet>(ctx);

    // Lay out every geometry's data in one input buffer. Indices and non-indexed vertices are addressed through
    // primitiveOffset and transforms through transformOffset, relative to the buffer's start.
    struct Placement {
        VkDeviceSize vertices = 0, indices = 0, transform = 0;
    };
    ByteWriter writer;
    std::vector<std::vector<Placement>> placements(blases.size());
    std::vector<PrimitivePlacement> primitivePlacements(blases.size());
    for (size_t b = 0; b < blases.size(); ++b) {
        if (blases[b].kind != PrimitiveKind::Triangles) {
            primitivePlacements[b] = placePrimitives(writer, blases[b]);
            continue;
        }
        for (const GeometryDesc& g : blases[b].geometries) {
            Placement p;
            p.vertices = writer.append(encodeVertices(*g.mesh, g.layout), 16);
            if (g.indexType == VK_INDEX_TYPE_UINT32) {
                p.indices = writer.append(g.mesh->indices, 4);
            } else if (g.indexType == VK_INDEX_TYPE_UINT16) {
                std::vector<uint16_t> narrow(g.mesh->indices.begin(), g.mesh->indices.end());
                p.indices = writer.append(narrow, 2);
            }
            if (g.transform) {
                VkTransformMatrixKHR m = g.transform->toVk();
                p.transform = writer.append(&m, sizeof m, 16);
            }
            placements[b].push_back(p);
        }
    }
    HostBuffer input(ctx, writer.bytes().size(), VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR);
    std::memcpy(input.data(), writer.bytes().data(), writer.bytes().size());
    set->inputBytes = writer.bytes().size();
    unsigned char* base = input.data();

    std::vector<std::vector<VkAccelerationStructureGeometryKHR>> geometries(blases.size());
    std::vector<std::vector<const VkAccelerationStructureGeometryKHR*>> geometryPointers(blases.size());
    std::vector<std::vector<VkAccelerationStructureBuildRangeInfoKHR>> ranges(blases.size());
    std::vector<std::vector<uint32_t>> counts(blases.size());
    std::vector<VkAccelerationStructureBuildGeometryInfoKHR> infos(blases.size());
    std::deque<PrimitiveData> primitiveData;  // pNext structures: stable addresses until the build
    for (size_t b = 0; b < blases.size(); ++b) {
        StructureStats stats;
        stats.name = blases[b].name;
        if (blases[b].kind != PrimitiveKind::Triangles) {
            primitiveData.emplace_back();
            VkAccelerationStructureBuildRangeInfoKHR range{};
            geometries[b].push_back(primitiveGeometry(blases[b], primitivePlacements[b], base, primitiveData.back(), range));
            ranges[b].push_back(range);
            counts[b].push_back(range.primitiveCount);
            stats.primitives += range.primitiveCount;
        }
        for (size_t gi = 0; gi < blases[b].geometries.size(); ++gi) {
            const GeometryDesc& g = blases[b].geometries[gi];
            const Placement& p = placements[b][gi];
            VertexEncoding enc = encodingOf(g.layout);
            VkAccelerationStructureGeometryKHR geom{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
            geom.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
            geom.flags = g.flags;
            auto& tri = geom.geometry.triangles;
            tri.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
            tri.vertexFormat = enc.format;
            tri.vertexStride = enc.stride;
            tri.maxVertex = static_cast<uint32_t>(g.mesh->positions.size() - 1);
            tri.indexType = g.indexType;
            VkAccelerationStructureBuildRangeInfoKHR range{};
            range.primitiveCount = g.mesh->triangleCount();
            if (g.indexType == VK_INDEX_TYPE_NONE_KHR) {
                tri.vertexData.hostAddress = base;  // primitiveOffset selects this geometry's vertices
                range.primitiveOffset = static_cast<uint32_t>(p.vertices);
            } else {
                tri.vertexData.hostAddress = base + p.vertices;
                tri.indexData.hostAddress = base;  // primitiveOffset selects this geometry's indices
                range.primitiveOffset = static_cast<uint32_t>(p.indices);
            }
            if (g.transform) {
                tri.transformData.hostAddress = base;
                range.transformOffset = static_cast<uint32_t>(p.transform);
            }
            geometries[b].push_back(geom);
            ranges[b].push_back(range);
            counts[b].push_back(range.primitiveCount);
            stats.primitives += range.primitiveCount;
        }
        for (const auto& geom : geometries[b]) geometryPointers[b].push_back(&geom);
        VkAccelerationStructureBuildGeometryInfoKHR& info = infos[b];
        info.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR;
        info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
        info.flags = flags;
        info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
        info.geometryCount = static_cast<uint32_t>(geometries[b].size());
        if (blases[b].usePointerArray)
            info.ppGeometries = geometryPointers[b].data();
        else
            info.pGeometries = geometries[b].data();
        set->stats.push_back(stats);
    }
    createAndBuild(ctx, *set, VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, infos, counts, ranges);
    return set;
}

std::unique_ptr<StructureSet> buildTopLevel(VkContext& ctx, const std::vector<InstanceDesc>& instances,
                                            const std::vector<VkAccelerationStructureKHR>& blases,
                                            VkBuildAccelerationStructureFlagsKHR flags) {
    auto set = std::make_unique<StructureSet>(ctx);
    HostBuffer input(ctx, instances.size() * sizeof(VkAccelerationStructureInstanceKHR),
                     VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR);
    set->inputBytes = input.size();
    auto* records = reinterpret_cast<VkAccelerationStructureInstanceKHR*>(input.data());
    for (size_t i = 0; i < instances.size(); ++i) {
        const InstanceDesc& d = instances[i];
        VkAccelerationStructureInstanceKHR r{};
        r.transform = d.transform.toVk();
        r.instanceCustomIndex = d.customIndex & 0xFFFFFFu;
        r.mask = d.mask;
        r.instanceShaderBindingTableRecordOffset = 0;
        r.flags = static_cast<uint8_t>(d.flags);
        // Host builds: the reference is the VkAccelerationStructureKHR handle itself.
        r.accelerationStructureReference = reinterpret_cast<uint64_t>(blases.at(d.blas));
        std::memcpy(&records[i], &r, sizeof r);
    }

    VkAccelerationStructureGeometryKHR geom{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    geom.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
    geom.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
    geom.geometry.instances.arrayOfPointers = VK_FALSE;
    geom.geometry.instances.data.hostAddress = input.data();

    std::vector<VkAccelerationStructureBuildGeometryInfoKHR> infos(1);
    infos[0].sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR;
    infos[0].type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
    infos[0].flags = flags;
    infos[0].mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
    infos[0].geometryCount = 1;
    infos[0].pGeometries = &geom;
    std::vector<std::vector<uint32_t>> counts = {{static_cast<uint32_t>(instances.size())}};
    VkAccelerationStructureBuildRangeInfoKHR range{};
    range.primitiveCount = static_cast<uint32_t>(instances.size());
    std::vector<std::vector<VkAccelerationStructureBuildRangeInfoKHR>> ranges = {{range}};
    set->stats.push_back({"top level", instances.size(), 0, 0});
    createAndBuild(ctx, *set, VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, infos, counts, ranges);
    return set;
}

}  // namespace vkas_tool
