#include "structure_file.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "input_error.hpp"
#include "vk_strings.hpp"

namespace vkas_tool {
namespace {

constexpr uint64_t kEnvelopeHeader = 56;  // UUIDs, serialized size, deserialized size, handle count

template <class T>
T load(const unsigned char* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

std::string printable(const unsigned char* p, size_t n) {
    std::string s;
    for (size_t i = 0; i < n; ++i) s += (p[i] >= 0x20 && p[i] < 0x7F) ? char(p[i]) : '?';
    return s;
}

// The file's bytes in 16-byte aligned storage (the copy commands' pointer rule).
std::vector<uint64_t> readAligned(const std::string& path, uint64_t& size) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw InputError(path, "no such file");
    if (std::filesystem::is_directory(path, ec)) throw InputError(path, "is a directory, not a file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, std::string("cannot be read: ") + std::strerror(errno));
    size = std::filesystem::file_size(path, ec);
    if (ec) throw InputError(path, "cannot be read: " + ec.message());
    checkMemory(3.0 * double(size), "loading " + path);
    std::vector<uint64_t> words((size + 15) / 16 * 2, 0);
    if (!in.read(reinterpret_cast<char*>(words.data()), static_cast<std::streamsize>(size)))
        throw InputError(path, "cannot be read to its end");
    return words;
}

}  // namespace

bool looksSerialized(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    char magic[5] = {};
    return in.read(magic, 5) && std::memcmp(magic, "VKAS-", 5) == 0;
}

LoadedStructure::~LoadedStructure() {
    if (handle != VK_NULL_HANDLE) ctx->vkDestroyAccelerationStructureKHR(ctx->device(), handle, nullptr);
}

LoadedStructure loadSerialized(VkContext& ctx, const std::string& path) {
    LoadedStructure out;
    std::vector<uint64_t> words = readAligned(path, out.fileSize);
    unsigned char* bytes = reinterpret_cast<unsigned char*>(words.data());
    const uint64_t size = out.fileSize;
    if (size == 0) throw InputError(path, "is empty");
    if (size < kEnvelopeHeader)
        throw InputError(path, "truncated: " + std::to_string(size) +
                                   " bytes, a serialized structure starts with a 56-byte header");
    SerializedHeader& h = out.header;
    h.driverUuid = printable(bytes, 16);
    h.compatibilityUuid = printable(bytes + 16, 16);
    h.serializedSize = load<uint64_t>(bytes + 32);
    h.deserializedSize = load<uint64_t>(bytes + 40);
    h.handleCount = load<uint64_t>(bytes + 48);
    h.layout = h.driverUuid == "VKAS-SERIALIZED2" ? 2 : h.driverUuid == "VKAS-DRIVER-FMT1" ? 1 : 0;

    // The UUIDs first, as deserialization checks them: a blob of another version gets its own message.
    VkAccelerationStructureVersionInfoKHR version{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_VERSION_INFO_KHR};
    version.pVersionData = bytes;
    VkAccelerationStructureCompatibilityKHR compatibility = VK_ACCELERATION_STRUCTURE_COMPATIBILITY_INCOMPATIBLE_KHR;
    ctx.vkGetDeviceAccelerationStructureCompatibilityKHR(ctx.device(), &version, &compatibility);
    if (compatibility != VK_ACCELERATION_STRUCTURE_COMPATIBILITY_COMPATIBLE_KHR)
        throw InputError(path, "not loadable by this vkas: driverUUID \"" + h.driverUuid + "\", compatibility UUID \"" +
                                   h.compatibilityUuid + "\" (vkGetDeviceAccelerationStructureCompatibilityKHR: INCOMPATIBLE)");
    if (size < h.serializedSize)
        throw InputError(path, "truncated: the file has " + std::to_string(size) + " bytes, its header says " +
                                   std::to_string(h.serializedSize));
    if (h.deserializedSize < 256 || h.deserializedSize > h.serializedSize ||
        h.handleCount > (h.serializedSize - kEnvelopeHeader) / 8)
        throw InputError(path, "corrupted: the sizes in its header disagree (serialized " +
                                   std::to_string(h.serializedSize) + ", deserialized " +
                                   std::to_string(h.deserializedSize) + ", " + std::to_string(h.handleCount) +
                                   " handles)");
    // The handle array is not covered by the hash: zero it, as the bottom levels it named are not here.
    std::memset(bytes + kEnvelopeHeader, 0, 8 * h.handleCount);

    out.ctx = &ctx;
    out.storage = std::make_unique<HostBuffer>(ctx, h.deserializedSize, VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR);
    std::memset(out.storage->data(), 0, h.deserializedSize);
    VkAccelerationStructureCreateInfoKHR aci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    aci.buffer = out.storage->buffer();
    aci.size = h.deserializedSize;
    aci.type = VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR;  // the serialized type decides
    check(ctx.vkCreateAccelerationStructureKHR(ctx.device(), &aci, nullptr, &out.handle),
          "vkCreateAccelerationStructureKHR");
    VkCopyMemoryToAccelerationStructureInfoKHR copy{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
    copy.src.hostAddress = bytes;
    copy.dst = out.handle;
    copy.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    const VkResult r = ctx.vkCopyMemoryToAccelerationStructureKHR(ctx.device(), VK_NULL_HANDLE, &copy);
    if (r != VK_SUCCESS) {
        std::string why = ctx.lastMessage();
        const size_t bar = why.find("| ");  // keep vkas's explanation, drop the message-id prefix
        if (bar != std::string::npos) why = why.substr(bar + 2);
        throw InputError(path, "corrupted or malformed: the integrity check failed (vkCopyMemoryToAccelerationStructureKHR: " +
                                   resultName(r) + (why.empty() ? ")" : "): " + why));
    }
    return out;
}

uint64_t queryStructureProperty(VkContext& ctx, VkAccelerationStructureKHR as, VkQueryType type) {
    uint64_t value = 0;
    check(ctx.vkWriteAccelerationStructuresPropertiesKHR(ctx.device(), 1, &as, type, sizeof value, &value, sizeof value),
          "vkWriteAccelerationStructuresPropertiesKHR");
    return value;
}

uint64_t writeSerialized(VkContext& ctx, VkAccelerationStructureKHR as, const std::string& path) {
    const uint64_t size = queryStructureProperty(ctx, as, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR);
    std::vector<uint64_t> words((size + 15) / 16 * 2, 0);
    VkCopyAccelerationStructureToMemoryInfoKHR copy{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
    copy.src = as;
    copy.dst.hostAddress = words.data();
    copy.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
    check(ctx.vkCopyAccelerationStructureToMemoryKHR(ctx.device(), VK_NULL_HANDLE, &copy),
          "vkCopyAccelerationStructureToMemoryKHR");
    std::ofstream out(path, std::ios::binary);
    if (!out || !out.write(reinterpret_cast<const char*>(words.data()), static_cast<std::streamsize>(size)))
        throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
    return size;
}

}  // namespace vkas_tool
