// vkas._core's builds: the geometry list from Python into VkAccelerationStructureGeometryKHR, builds and updates
// (through a deferred operation on the device's threads for large ones) and the Device's build_bottom, update_bottom,
// build_top and update_top.
#include <thread>

#include "arrays.hpp"

namespace vkas_python {

namespace {

struct GeometryInputs {
    std::vector<VkAccelerationStructureGeometryKHR> geometries;
    std::vector<VkAccelerationStructureGeometrySpheresDataNV> spheres;
    std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges;
    std::vector<uint32_t> counts;
    std::vector<py::array> keep;  // the arrays read by the build
    uint64_t primitives = 0;
};

// geometries: a list of (0, vertices (N,3) f32, indices (M,3) u16/u32 or None, transform (3,4) f32 or None, opaque)
// and (1, centers (N,3) f32, radii (N,) f32, opaque).
GeometryInputs parseGeometries(const py::list& list) {
    GeometryInputs in;
    const size_t n = list.size();
    in.geometries.reserve(n);
    in.spheres.reserve(n);
    for (size_t i = 0; i < n; ++i) {
        py::tuple t = list[i].cast<py::tuple>();
        const int kind = t[0].cast<int>();
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        // Every primitive is reported at most once to intersect_all's ray queries.
        g.flags = VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR;
        uint32_t count = 0;
        if (kind == 0) {
            if (t.size() != 5) throw py::value_error("vkas._core: a triangle geometry is a 5-tuple");
            py::array v = t[1].cast<py::array>();
            const float* vp = arrayData<float>(v, "vertices", {-1, 3});
            const py::ssize_t nv = v.shape(0);
            in.keep.push_back(v);
            g.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
            auto& tr = g.geometry.triangles;
            tr.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
            tr.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
            tr.vertexData.hostAddress = vp;
            tr.vertexStride = 12;
            tr.maxVertex = nv > 0 ? uint32_t(nv - 1) : 0;
            if (t[2].is_none()) {
                tr.indexType = VK_INDEX_TYPE_NONE_KHR;
                count = uint32_t(nv / 3);
            } else {
                py::array idx = t[2].cast<py::array>();
                in.keep.push_back(idx);
                if (idx.dtype().is(py::dtype::of<uint16_t>())) {
                    tr.indexType = VK_INDEX_TYPE_UINT16;
                    tr.indexData.hostAddress = arrayData<uint16_t>(idx, "indices", {-1, 3});
                } else {
                    tr.indexType = VK_INDEX_TYPE_UINT32;
                    tr.indexData.hostAddress = arrayData<uint32_t>(idx, "indices", {-1, 3});
                }
                count = uint32_t(idx.shape(0));
            }
            if (!t[3].is_none()) {
                py::array xf = t[3].cast<py::array>();
                in.keep.push_back(xf);
                tr.transformData.hostAddress = arrayData<float>(xf, "transform", {3, 4});
            }
            if (t[4].cast<bool>()) g.flags |= VK_GEOMETRY_OPAQUE_BIT_KHR;
        } else if (kind == 1) {
            if (t.size() != 4) throw py::value_error("vkas._core: a sphere geometry is a 4-tuple");
            py::array c = t[1].cast<py::array>(), r = t[2].cast<py::array>();
            const float* cp = arrayData<float>(c, "centers", {-1, 3});
            const float* rp = arrayData<float>(r, "radii", {c.shape(0)});
            in.keep.push_back(c);
            in.keep.push_back(r);
            VkAccelerationStructureGeometrySpheresDataNV sp{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV};
            sp.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
            sp.vertexData.hostAddress = cp;
            sp.vertexStride = 12;
            sp.radiusFormat = VK_FORMAT_R32_SFLOAT;
            sp.radiusData.hostAddress = rp;
            sp.radiusStride = 4;
            sp.indexType = VK_INDEX_TYPE_NONE_KHR;
            in.spheres.push_back(sp);
            g.pNext = &in.spheres.back();  // reserved above: no reallocation
            g.geometryType = VK_GEOMETRY_TYPE_SPHERES_NV;
            count = uint32_t(c.shape(0));
            if (t[3].cast<bool>()) g.flags |= VK_GEOMETRY_OPAQUE_BIT_KHR;
        } else {
            throw py::value_error("vkas._core: unknown geometry kind " + std::to_string(kind));
        }
        in.geometries.push_back(g);
        in.ranges.push_back({count, 0, 0, 0});
        in.counts.push_back(count);
        in.primitives += count;
    }
    return in;
}

// Runs one build (or update). With more than one thread and enough primitives, through a deferred operation joined
// by the device's threads: the bytes are the same either way (docs/API.md, section 7).
void runBuild(DeviceImpl& d, const VkAccelerationStructureBuildGeometryInfoKHR& info,
              const VkAccelerationStructureBuildRangeInfoKHR* ranges, uint64_t primitives) {
    Capture capture;
    const VkAccelerationStructureBuildRangeInfoKHR* pRanges = ranges;
    const unsigned threads = primitives >= 16384 ? d.threads : 1;
    if (threads <= 1 || info.mode == VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR) {
        capture.check(d.vkBuildAccelerationStructuresKHR(d.device, VK_NULL_HANDLE, 1, &info, &pRanges),
                      "vkBuildAccelerationStructuresKHR");
        return;
    }
    VkDeferredOperationKHR op = VK_NULL_HANDLE;
    capture.check(d.vkCreateDeferredOperationKHR(d.device, nullptr, &op), "vkCreateDeferredOperationKHR");
    struct OpGuard {
        DeviceImpl& d;
        VkDeferredOperationKHR op;
        ~OpGuard() { d.vkDestroyDeferredOperationKHR(d.device, op, nullptr); }
    } guard{d, op};
    const VkResult r = d.vkBuildAccelerationStructuresKHR(d.device, op, 1, &info, &pRanges);
    if (r != VK_OPERATION_DEFERRED_KHR) {
        capture.check(r, "vkBuildAccelerationStructuresKHR");
        return;
    }
    auto join = [&] {
        while (d.vkDeferredOperationJoinKHR(d.device, op) == VK_THREAD_IDLE_KHR) std::this_thread::yield();
    };
    std::vector<std::thread> pool;
    for (unsigned k = 1; k < threads; ++k) pool.emplace_back(join);
    join();
    for (auto& t : pool) t.join();
    capture.check(d.vkGetDeferredOperationResultKHR(d.device, op), "vkBuildAccelerationStructuresKHR (deferred)");
}

VkAccelerationStructureBuildGeometryInfoKHR buildInfo(VkAccelerationStructureTypeKHR type, uint32_t flags,
                                                      const std::vector<VkAccelerationStructureGeometryKHR>& g) {
    VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    info.type = type;
    info.flags = flags;
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
    info.geometryCount = uint32_t(g.size());
    info.pGeometries = g.data();
    return info;
}

StructurePtr buildNew(const std::shared_ptr<DeviceImpl>& d, VkAccelerationStructureTypeKHR type, uint32_t flags,
                      const std::vector<VkAccelerationStructureGeometryKHR>& geometries,
                      const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges,
                      const std::vector<uint32_t>& counts, uint64_t primitives) {
    VkAccelerationStructureBuildGeometryInfoKHR info = buildInfo(type, flags, geometries);
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    {
        Capture capture;
        d->vkGetAccelerationStructureBuildSizesKHR(d->device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info,
                                                   counts.data(), &sizes);
        capture.check("vkGetAccelerationStructureBuildSizesKHR");
    }
    if (sizes.accelerationStructureSize == 0) throw std::runtime_error("vkGetAccelerationStructureBuildSizesKHR gave 0");
    auto s = std::make_shared<Structure>(d, type, sizes.accelerationStructureSize);
    std::unique_ptr<unsigned char[]> scratch(new unsigned char[std::max<VkDeviceSize>(sizes.buildScratchSize, 16)]);
    info.dstAccelerationStructure = s->as;
    info.scratchData.hostAddress = scratch.get();
    runBuild(*d, info, ranges.data(), primitives);
    return s;
}

void updateInPlace(const std::shared_ptr<DeviceImpl>& d, Structure& s, VkAccelerationStructureTypeKHR type,
                   uint32_t flags, const std::vector<VkAccelerationStructureGeometryKHR>& geometries,
                   const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges) {
    VkAccelerationStructureBuildGeometryInfoKHR info = buildInfo(type, flags, geometries);
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
    info.srcAccelerationStructure = info.dstAccelerationStructure = s.as;
    unsigned char scratch[16];  // updateScratchSize is 0
    info.scratchData.hostAddress = scratch;
    runBuild(*d, info, ranges.data(), 0);
}

}  // namespace

StructurePtr Device::buildBottom(const py::list& geometries, uint32_t flags) {
    GeometryInputs in = parseGeometries(geometries);
    py::gil_scoped_release release;
    return buildNew(d, VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, flags, in.geometries, in.ranges, in.counts,
                    in.primitives);
}

void Device::updateBottom(const StructurePtr& s, const py::list& geometries, uint32_t flags) {
    GeometryInputs in = parseGeometries(geometries);
    py::gil_scoped_release release;
    updateInPlace(d, *s, VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, flags, in.geometries, in.ranges);
}

// records: the VkAccelerationStructureInstanceKHR array, as a bytes-like object of 64 * count bytes.
VkAccelerationStructureGeometryKHR Device::instanceGeometry(const py::buffer_info& b, uint32_t& count) {
    if (b.size * b.itemsize % 64 != 0) throw py::value_error("records: not a whole number of 64-byte records");
    count = uint32_t(b.size * b.itemsize / 64);
    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    g.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
    g.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
    g.geometry.instances.arrayOfPointers = VK_FALSE;
    g.geometry.instances.data.hostAddress = b.ptr;
    return g;
}

StructurePtr Device::buildTop(const py::buffer& records, uint32_t flags) {
    py::buffer_info b = records.request();
    uint32_t count = 0;
    std::vector<VkAccelerationStructureGeometryKHR> g{instanceGeometry(b, count)};
    std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges{{count, 0, 0, 0}};
    std::vector<uint32_t> counts{count};
    py::gil_scoped_release release;
    return buildNew(d, VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, flags, g, ranges, counts, count);
}

void Device::updateTop(const StructurePtr& s, const py::buffer& records, uint32_t flags) {
    py::buffer_info b = records.request();
    uint32_t count = 0;
    std::vector<VkAccelerationStructureGeometryKHR> g{instanceGeometry(b, count)};
    std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges{{count, 0, 0, 0}};
    py::gil_scoped_release release;
    updateInPlace(d, *s, VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, flags, g, ranges);
}

}  // namespace vkas_python
