// vkas._core's structures: Structure (an acceleration structure with its own buffer and memory: creation, release,
// device address, reads, property queries) and the Device's copies, serialization and deserialization.
#include <cstring>

#include "core.hpp"

namespace vkas_python {

namespace {

// Host memory aligned to 16 bytes (the copy commands' pointer rule for serialized data).
struct Aligned {
    struct alignas(16) Chunk {
        unsigned char b[16];
    };
    std::unique_ptr<Chunk[]> chunks;
    size_t size = 0;
    explicit Aligned(size_t n) : chunks(new Chunk[(n + 15) / 16 + 1]), size(n) {}
    unsigned char* data() { return chunks[0].b; }
};

}  // namespace

Structure::Structure(std::shared_ptr<DeviceImpl> dev, VkAccelerationStructureTypeKHR type, VkDeviceSize bytes)
    : d(std::move(dev)), size(std::max<VkDeviceSize>(bytes, 256)) {
    Capture capture;
    VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bci.size = size;
    bci.usage = VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
    try {
        capture.check(d->vkCreateBuffer(d->device, &bci, nullptr, &buffer), "vkCreateBuffer");
        VkMemoryRequirements req{};
        d->vkGetBufferMemoryRequirements(d->device, buffer, &req);
        VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        mai.allocationSize = req.size;
        mai.memoryTypeIndex = 0;
        VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
        flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
        mai.pNext = &flags;
        capture.check(d->vkAllocateMemory(d->device, &mai, nullptr, &memory), "vkAllocateMemory");
        capture.check(d->vkBindBufferMemory(d->device, buffer, memory, 0), "vkBindBufferMemory");
        void* p = nullptr;
        capture.check(d->vkMapMemory(d->device, memory, 0, VK_WHOLE_SIZE, 0, &p), "vkMapMemory");
        mapped = static_cast<const unsigned char*>(p);
        VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
        ci.buffer = buffer;
        ci.size = size;
        ci.type = type;
        capture.check(d->vkCreateAccelerationStructureKHR(d->device, &ci, nullptr, &as),
                      "vkCreateAccelerationStructureKHR");
    } catch (...) {
        release();
        throw;
    }
}

void Structure::release() {
    Capture capture;  // nothing should be reported; whatever is, is dropped with the object
    if (as) d->vkDestroyAccelerationStructureKHR(d->device, as, nullptr);
    if (buffer) d->vkDestroyBuffer(d->device, buffer, nullptr);
    if (memory) d->vkFreeMemory(d->device, memory, nullptr);
    as = VK_NULL_HANDLE, buffer = VK_NULL_HANDLE, memory = VK_NULL_HANDLE, mapped = nullptr;
}

uint64_t Structure::address() const {
    VkAccelerationStructureDeviceAddressInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
    info.accelerationStructure = as;
    Capture capture;
    const uint64_t a = d->vkGetAccelerationStructureDeviceAddressKHR(d->device, &info);
    capture.check("vkGetAccelerationStructureDeviceAddressKHR");
    return a;
}

py::bytes Structure::read(uint64_t offset, uint64_t count) const {
    const uint64_t used = std::min<uint64_t>(usedSize(), size);
    if (!constructed() || offset > used || count > used - offset)
        throw py::value_error("read: [" + std::to_string(offset) + ", +" + std::to_string(count) +
                              ") is outside the structure's " + std::to_string(used) + " bytes");
    return py::bytes(reinterpret_cast<const char*>(mapped + offset), size_t(count));
}

uint64_t Structure::query(VkQueryType type) const {
    uint64_t value = 0;
    Capture capture;
    capture.check(d->vkWriteAccelerationStructuresPropertiesKHR(d->device, 1, &as, type, sizeof value, &value,
                                                                  sizeof value),
                  "vkWriteAccelerationStructuresPropertiesKHR");
    return value;
}

// A copy of `src` (COMPACT or CLONE) into a structure of exactly the size the copy needs.
StructurePtr Device::copy(const StructurePtr& src, bool compact) {
    py::gil_scoped_release release;
    const uint64_t bytes = src->query(compact ? VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR
                                              : VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR);
    auto dst = std::make_shared<Structure>(d, VkAccelerationStructureTypeKHR(src->type()), bytes);
    VkCopyAccelerationStructureInfoKHR info{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
    info.src = src->as;
    info.dst = dst->as;
    info.mode = compact ? VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR : VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR;
    Capture capture;
    capture.check(d->vkCopyAccelerationStructureKHR(d->device, VK_NULL_HANDLE, &info), "vkCopyAccelerationStructureKHR");
    return dst;
}

py::bytes Device::serialize(const StructurePtr& s) {
    std::unique_ptr<Aligned> out;
    {
        py::gil_scoped_release release;
        const uint64_t bytes = s->query(VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR);
        out = std::make_unique<Aligned>(size_t(bytes));
        VkCopyAccelerationStructureToMemoryInfoKHR info{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
        info.src = s->as;
        info.dst.hostAddress = out->data();
        info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
        Capture capture;
        capture.check(d->vkCopyAccelerationStructureToMemoryKHR(d->device, VK_NULL_HANDLE, &info),
                      "vkCopyAccelerationStructureToMemoryKHR");
    }
    return py::bytes(reinterpret_cast<const char*>(out->data()), out->size);
}

// blob: a serialized structure. With replace, bottoms gives the handle array to write: one structure per entry
// (its device address; null for 0, an inactive instance); without, the blob must have no entries.
StructurePtr Device::deserialize(const py::buffer& blob, const std::vector<StructurePtr>& bottoms, bool replace) {
    py::buffer_info b = blob.request();
    // The bytes are read as one run from b.ptr: a strided view (a reversed memoryview) would be read outside it.
    py::ssize_t expected = b.itemsize;
    for (py::ssize_t k = b.ndim - 1; k >= 0; --k) {
        if (b.shape[size_t(k)] > 1 && b.strides[size_t(k)] != expected)
            throw py::value_error("blob: not C-contiguous: pass bytes(blob)");
        expected *= b.shape[size_t(k)];
    }
    const uint64_t n = uint64_t(b.size) * uint64_t(b.itemsize);
    if (n < 64) throw py::value_error("blob: " + std::to_string(n) + " bytes is too short for a serialized structure");
    auto load = [&](size_t off) {
        uint64_t v;
        std::memcpy(&v, static_cast<const unsigned char*>(b.ptr) + off, 8);
        return v;
    };
    const uint64_t serialized = load(32), deserialized = load(40), handles = load(48);
    if (serialized > n)
        throw py::value_error("blob: truncated: " + std::to_string(n) + " bytes, its header says " +
                              std::to_string(serialized));
    if (deserialized > serialized || handles > (serialized - 56) / 8)
        throw py::value_error("blob: corrupted: the sizes in its header disagree");
    if (replace && bottoms.size() != handles)
        throw py::value_error("bottom_levels: the blob's top level has " + std::to_string(handles) +
                              " instances, " + std::to_string(bottoms.size()) + " bottom levels were given");
    if (!replace && handles != 0)
        throw py::value_error("bottom_levels: the blob is a top level with " + std::to_string(handles) +
                              " instances: give the bottom level of each (None for an inactive one)");
    Aligned copy{size_t(serialized)};
    std::memcpy(copy.data(), b.ptr, size_t(serialized));
    for (uint64_t k = 0; k < handles; ++k) {
        const uint64_t a = bottoms[k] ? bottoms[k]->address() : 0;
        std::memcpy(copy.data() + 56 + 8 * k, &a, 8);
    }
    py::gil_scoped_release release;
    auto dst = std::make_shared<Structure>(d, VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR, deserialized);
    VkCopyMemoryToAccelerationStructureInfoKHR info{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
    info.src.hostAddress = copy.data();
    info.dst = dst->as;
    info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    Capture capture;
    const VkResult r = d->vkCopyMemoryToAccelerationStructureKHR(d->device, VK_NULL_HANDLE, &info);
    if (r == VK_ERROR_UNKNOWN && capture.messages.empty())  // validation off: the data is checked all the same
        throw py::value_error("blob: not a valid serialized structure (corrupted, malformed or truncated; "
                              "vkCopyMemoryToAccelerationStructureKHR: VK_ERROR_UNKNOWN)");
    if (r == VK_ERROR_INCOMPATIBLE_VERSION_KHR && capture.messages.empty())
        throw py::value_error("blob: serialized by an incompatible vkas (VK_ERROR_INCOMPATIBLE_VERSION_KHR)");
    capture.check(r, "vkCopyMemoryToAccelerationStructureKHR");
    return dst;
}

}  // namespace vkas_python
