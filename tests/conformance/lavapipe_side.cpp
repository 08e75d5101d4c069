#include "lavapipe_side.hpp"

#include <vkas/vkas_compat.h>  // VK_KHR_ray_tracing_position_fetch, newer than Debian 12's Vulkan header

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <stdexcept>

// SPIR-V of shaders/ray_program.comp, generated at build time by glslangValidator: with and without position fetch.
#include "ray_program_fetch.hpp"
#include "ray_program_nofetch.hpp"

namespace diff {

namespace {

// Commands of device extensions, which the loader does not export.
#define LVP_DEVICE_COMMANDS(X)                    \
    X(vkGetAccelerationStructureBuildSizesKHR)    \
    X(vkCreateAccelerationStructureKHR)           \
    X(vkDestroyAccelerationStructureKHR)          \
    X(vkGetAccelerationStructureDeviceAddressKHR) \
    X(vkCmdBuildAccelerationStructuresKHR)

struct DeviceCommands {
#define LVP_DECLARE(name) PFN_##name name = nullptr;
    LVP_DEVICE_COMMANDS(LVP_DECLARE)
#undef LVP_DECLARE
};

const char* resultName(VkResult r) {
    switch (r) {
        case VK_SUCCESS: return "VK_SUCCESS";
        case VK_NOT_READY: return "VK_NOT_READY";
        case VK_TIMEOUT: return "VK_TIMEOUT";
        case VK_INCOMPLETE: return "VK_INCOMPLETE";
        case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
        case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
        case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
        case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST";
        case VK_ERROR_MEMORY_MAP_FAILED: return "VK_ERROR_MEMORY_MAP_FAILED";
        case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
        case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
        case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
        case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER";
        case VK_ERROR_TOO_MANY_OBJECTS: return "VK_ERROR_TOO_MANY_OBJECTS";
        case VK_ERROR_OUT_OF_POOL_MEMORY: return "VK_ERROR_OUT_OF_POOL_MEMORY";
        case VK_ERROR_INVALID_OPAQUE_CAPTURE_ADDRESS: return "VK_ERROR_INVALID_OPAQUE_CAPTURE_ADDRESS";
        default: return "VkResult";
    }
}

void check(VkResult r, const char* what) {
    if (r != VK_SUCCESS)
        throw std::runtime_error(std::string("lavapipe: ") + what + " failed: " + resultName(r) + " (" +
                                 std::to_string(int(r)) + ")");
}

VkDeviceSize alignUp(VkDeviceSize value, VkDeviceSize alignment) {
    return (value + alignment - 1) / alignment * alignment;
}

bool hasExtension(const std::vector<VkExtensionProperties>& extensions, const char* name) {
    return std::any_of(extensions.begin(), extensions.end(),
                       [&](const VkExtensionProperties& e) { return std::strcmp(e.extensionName, name) == 0; });
}

// Bindings of ray_program.comp: 0 the TLAS; then storage buffers: 1 rays, 2 results, 3 to 7 the procedural tables
// in the order of ProceduralTables' members.
constexpr uint32_t kTableCount = 5, kStorageBufferCount = 2 + kTableCount;
constexpr uint32_t kLocalSize = 64;  // local_size_x of ray_program.comp

// The instance, the lavapipe device and the ray-program pipeline, kept for the side's whole life.
struct Context {
    VkInstance instance = VK_NULL_HANDLE;
    VkPhysicalDevice physical = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    VkQueue queue = VK_NULL_HANDLE;
    DeviceCommands vk;
    VkPhysicalDeviceMemoryProperties memory{};
    VkPhysicalDeviceAccelerationStructurePropertiesKHR asProperties{};
    uint32_t maxDispatchGroups = 0;
    std::string description;
    bool positionFetch = false;
    bool opacityMicromap = false;  // VK_EXT_opacity_micromap exposed with the micromap feature (never enabled)

    VkDescriptorSetLayout setLayout = VK_NULL_HANDLE;
    VkPipelineLayout pipelineLayout = VK_NULL_HANDLE;
    VkPipeline pipeline = VK_NULL_HANDLE;
    VkDescriptorPool descriptorPool = VK_NULL_HANDLE;
    VkDescriptorSet descriptorSet = VK_NULL_HANDLE;
    VkCommandPool commandPool = VK_NULL_HANDLE;
    VkCommandBuffer commandBuffer = VK_NULL_HANDLE;
    VkFence fence = VK_NULL_HANDLE;

    ~Context() {
        if (device) {
            vkDeviceWaitIdle(device);
            vkDestroyFence(device, fence, nullptr);
            vkDestroyCommandPool(device, commandPool, nullptr);
            vkDestroyDescriptorPool(device, descriptorPool, nullptr);
            vkDestroyPipeline(device, pipeline, nullptr);
            vkDestroyPipelineLayout(device, pipelineLayout, nullptr);
            vkDestroyDescriptorSetLayout(device, setLayout, nullptr);
            vkDestroyDevice(device, nullptr);
        }
        if (instance) vkDestroyInstance(instance, nullptr);
    }

    // Picks lavapipe among the physical devices; returns false with the reason when it is absent or lacks a feature.
    bool choosePhysicalDevice(std::string* why);
    void createDevice();
    void createPipeline();
    uint32_t hostMemoryType(uint32_t allowedTypes) const;
};

// A buffer in HOST_VISIBLE | HOST_COHERENT memory (lavapipe's memory is host memory), mapped for its whole life.
class DeviceBuffer {
  public:
    DeviceBuffer(const Context& s, VkDeviceSize size, VkBufferUsageFlags usage);
    ~DeviceBuffer() {
        vkDestroyBuffer(device_, buffer, nullptr);
        vkFreeMemory(device_, memory, nullptr);
    }
    DeviceBuffer(const DeviceBuffer&) = delete;
    DeviceBuffer& operator=(const DeviceBuffer&) = delete;

    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    uint8_t* mapped = nullptr;
    VkDeviceAddress address = 0;  // 0 unless the usage has SHADER_DEVICE_ADDRESS

  private:
    VkDevice device_;
};

uint32_t Context::hostMemoryType(uint32_t allowedTypes) const {
    const VkMemoryPropertyFlags wanted = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    for (uint32_t i = 0; i < memory.memoryTypeCount; ++i)
        if ((allowedTypes & (1u << i)) && (memory.memoryTypes[i].propertyFlags & wanted) == wanted) return i;
    throw std::runtime_error("lavapipe: no HOST_VISIBLE | HOST_COHERENT memory type for a buffer");
}

DeviceBuffer::DeviceBuffer(const Context& s, VkDeviceSize size, VkBufferUsageFlags usage) : device_(s.device) {
    VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bci.size = std::max<VkDeviceSize>(size, 4);
    bci.usage = usage;
    bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    check(vkCreateBuffer(device_, &bci, nullptr, &buffer), "vkCreateBuffer");
    try {
        VkMemoryRequirements req;
        vkGetBufferMemoryRequirements(device_, buffer, &req);
        VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
        flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
        VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, &flags};
        mai.allocationSize = req.size;
        mai.memoryTypeIndex = s.hostMemoryType(req.memoryTypeBits);
        check(vkAllocateMemory(device_, &mai, nullptr, &memory), "vkAllocateMemory");
        check(vkBindBufferMemory(device_, buffer, memory, 0), "vkBindBufferMemory");
        void* p = nullptr;
        check(vkMapMemory(device_, memory, 0, VK_WHOLE_SIZE, 0, &p), "vkMapMemory");
        mapped = static_cast<uint8_t*>(p);
        if (usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT) {
            VkBufferDeviceAddressInfo bai{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
            bai.buffer = buffer;
            address = vkGetBufferDeviceAddress(device_, &bai);
        }
    } catch (...) {
        vkDestroyBuffer(device_, buffer, nullptr);
        vkFreeMemory(device_, memory, nullptr);
        throw;
    }
}

bool Context::choosePhysicalDevice(std::string* why) {
    const std::string hint =
        " (is mesa-vulkan-drivers >= 25 installed, and VK_ICD_FILENAMES / VK_DRIVER_FILES set to lvp_icd.json?)";
    uint32_t count = 0;
    VkResult r = vkEnumeratePhysicalDevices(instance, &count, nullptr);
    std::vector<VkPhysicalDevice> devices(count);
    if (r == VK_SUCCESS) r = vkEnumeratePhysicalDevices(instance, &count, devices.data());
    if (r != VK_SUCCESS) {  // the loader's answer when no driver loads
        if (why) *why = std::string("vkEnumeratePhysicalDevices failed: ") + resultName(r) + hint;
        return false;
    }
    std::string rejected;
    for (VkPhysicalDevice pd : devices) {
        VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
        VkPhysicalDeviceAccelerationStructurePropertiesKHR as{
            VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_PROPERTIES_KHR, &driver};
        VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &as};
        vkGetPhysicalDeviceProperties2(pd, &props);
        const std::string name = props.properties.deviceName;
        auto reject = [&](const std::string& reason) { rejected += "; " + name + ": " + reason; };
        // Only lavapipe: the differential tests compare vkas with this one driver, and a hardware driver picked by
        // accident would make every difference in rounding a mismatch.
        if (driver.driverID != VK_DRIVER_ID_MESA_LLVMPIPE) {
            reject("not lavapipe");
            continue;
        }
        if (props.properties.apiVersion < VK_API_VERSION_1_2) {
            reject("Vulkan 1.2 not supported");
            continue;
        }
        uint32_t extCount = 0;
        check(vkEnumerateDeviceExtensionProperties(pd, nullptr, &extCount, nullptr),
              "vkEnumerateDeviceExtensionProperties");
        std::vector<VkExtensionProperties> extensions(extCount);
        check(vkEnumerateDeviceExtensionProperties(pd, nullptr, &extCount, extensions.data()),
              "vkEnumerateDeviceExtensionProperties");
        std::string missing;
        for (const char* e : {VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME, VK_KHR_RAY_QUERY_EXTENSION_NAME,
                              VK_KHR_DEFERRED_HOST_OPERATIONS_EXTENSION_NAME})
            if (!hasExtension(extensions, e)) missing += std::string(missing.empty() ? "" : ", ") + e;
        if (!missing.empty()) {
            reject("lacks " + missing);
            continue;
        }
        const bool fetchExtension = hasExtension(extensions, VK_KHR_RAY_TRACING_POSITION_FETCH_EXTENSION_NAME);
        const bool micromapExtension = hasExtension(extensions, VK_EXT_OPACITY_MICROMAP_EXTENSION_NAME);

        VkPhysicalDeviceRayTracingPositionFetchFeaturesKHR fetch{
            VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_POSITION_FETCH_FEATURES_KHR};
        VkPhysicalDeviceRayQueryFeaturesKHR rayQuery{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_QUERY_FEATURES_KHR,
                                                     fetchExtension ? &fetch : nullptr};
        VkPhysicalDeviceAccelerationStructureFeaturesKHR asFeatures{
            VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR, &rayQuery};
        VkPhysicalDeviceVulkan12Features v12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES, &asFeatures};
        VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &v12};
        vkGetPhysicalDeviceFeatures2(pd, &features);
        VkPhysicalDeviceOpacityMicromapFeaturesEXT micromap{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_OPACITY_MICROMAP_FEATURES_EXT};
        if (micromapExtension) {
            VkPhysicalDeviceFeatures2 micromapFeatures{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &micromap};
            vkGetPhysicalDeviceFeatures2(pd, &micromapFeatures);
        }
        if (!v12.bufferDeviceAddress || !asFeatures.accelerationStructure || !rayQuery.rayQuery) {
            reject("lacks the bufferDeviceAddress, accelerationStructure or rayQuery feature");
            continue;
        }
        physical = pd;
        positionFetch = fetchExtension && fetch.rayTracingPositionFetch;
        opacityMicromap = micromapExtension && micromap.micromap;
        asProperties = as;
        asProperties.pNext = nullptr;
        maxDispatchGroups = props.properties.limits.maxComputeWorkGroupCount[0];
        description = name + ", " + driver.driverInfo;
        vkGetPhysicalDeviceMemoryProperties(pd, &memory);
        return true;
    }
    if (why)
        *why = "no lavapipe device with ray queries among the " + std::to_string(count) + " Vulkan physical device(s)" +
               rejected + hint;
    return false;
}

void Context::createDevice() {
    uint32_t familyCount = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(physical, &familyCount, nullptr);
    std::vector<VkQueueFamilyProperties> families(familyCount);
    vkGetPhysicalDeviceQueueFamilyProperties(physical, &familyCount, families.data());
    uint32_t family = 0;
    while (family < familyCount && !(families[family].queueFlags & VK_QUEUE_COMPUTE_BIT)) ++family;
    if (family == familyCount) throw std::runtime_error("lavapipe: no compute queue family");

    const float priority = 1.0f;
    VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qci.queueFamilyIndex = family;
    qci.queueCount = 1;
    qci.pQueuePriorities = &priority;

    std::vector<const char*> extensions = {VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME,
                                           VK_KHR_RAY_QUERY_EXTENSION_NAME,
                                           VK_KHR_DEFERRED_HOST_OPERATIONS_EXTENSION_NAME};
    if (positionFetch) extensions.push_back(VK_KHR_RAY_TRACING_POSITION_FETCH_EXTENSION_NAME);

    VkPhysicalDeviceRayTracingPositionFetchFeaturesKHR fetch{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_POSITION_FETCH_FEATURES_KHR};
    fetch.rayTracingPositionFetch = VK_TRUE;
    VkPhysicalDeviceRayQueryFeaturesKHR rayQuery{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_QUERY_FEATURES_KHR,
                                                 positionFetch ? &fetch : nullptr};
    rayQuery.rayQuery = VK_TRUE;
    VkPhysicalDeviceAccelerationStructureFeaturesKHR asFeatures{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR, &rayQuery};
    asFeatures.accelerationStructure = VK_TRUE;
    VkPhysicalDeviceVulkan12Features v12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES, &asFeatures};
    v12.bufferDeviceAddress = VK_TRUE;
    VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &v12};

    VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, &features};
    dci.queueCreateInfoCount = 1;
    dci.pQueueCreateInfos = &qci;
    dci.enabledExtensionCount = uint32_t(extensions.size());
    dci.ppEnabledExtensionNames = extensions.data();
    check(vkCreateDevice(physical, &dci, nullptr, &device), "vkCreateDevice");
    vkGetDeviceQueue(device, family, 0, &queue);

#define LVP_LOAD(name)                                                          \
    vk.name = reinterpret_cast<PFN_##name>(vkGetDeviceProcAddr(device, #name)); \
    if (!vk.name) throw std::runtime_error("lavapipe: vkGetDeviceProcAddr returned NULL for " #name);
    LVP_DEVICE_COMMANDS(LVP_LOAD)
#undef LVP_LOAD

    VkCommandPoolCreateInfo cpci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    cpci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    cpci.queueFamilyIndex = family;
    check(vkCreateCommandPool(device, &cpci, nullptr, &commandPool), "vkCreateCommandPool");
    VkCommandBufferAllocateInfo cbai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    cbai.commandPool = commandPool;
    cbai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    cbai.commandBufferCount = 1;
    check(vkAllocateCommandBuffers(device, &cbai, &commandBuffer), "vkAllocateCommandBuffers");
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    check(vkCreateFence(device, &fci, nullptr, &fence), "vkCreateFence");
}

void Context::createPipeline() {
    std::vector<VkDescriptorSetLayoutBinding> bindings;
    bindings.push_back({0, VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
    for (uint32_t b = 1; b <= kStorageBufferCount; ++b)
        bindings.push_back({b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
    VkDescriptorSetLayoutCreateInfo dslci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    dslci.bindingCount = uint32_t(bindings.size());
    dslci.pBindings = bindings.data();
    check(vkCreateDescriptorSetLayout(device, &dslci, nullptr, &setLayout), "vkCreateDescriptorSetLayout");

    const VkPushConstantRange pushRange{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(uint32_t)};  // rayCount
    VkPipelineLayoutCreateInfo plci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    plci.setLayoutCount = 1;
    plci.pSetLayouts = &setLayout;
    plci.pushConstantRangeCount = 1;
    plci.pPushConstantRanges = &pushRange;
    check(vkCreatePipelineLayout(device, &plci, nullptr, &pipelineLayout), "vkCreatePipelineLayout");

    VkShaderModuleCreateInfo smci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    smci.codeSize = positionFetch ? sizeof ray_program_fetch : sizeof ray_program_nofetch;
    smci.pCode = positionFetch ? ray_program_fetch : ray_program_nofetch;
    VkShaderModule module = VK_NULL_HANDLE;
    check(vkCreateShaderModule(device, &smci, nullptr, &module), "vkCreateShaderModule");
    VkComputePipelineCreateInfo cpci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    cpci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    cpci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    cpci.stage.module = module;
    cpci.stage.pName = "main";
    cpci.layout = pipelineLayout;
    const VkResult r = vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &cpci, nullptr, &pipeline);
    vkDestroyShaderModule(device, module, nullptr);
    check(r, "vkCreateComputePipelines (ray_program.comp)");

    const VkDescriptorPoolSize poolSizes[] = {{VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR, 1},
                                              {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kStorageBufferCount}};
    VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    dpci.maxSets = 1;
    dpci.poolSizeCount = 2;
    dpci.pPoolSizes = poolSizes;
    check(vkCreateDescriptorPool(device, &dpci, nullptr, &descriptorPool), "vkCreateDescriptorPool");
    VkDescriptorSetAllocateInfo dsai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    dsai.descriptorPool = descriptorPool;
    dsai.descriptorSetCount = 1;
    dsai.pSetLayouts = &setLayout;
    check(vkAllocateDescriptorSets(device, &dsai, &descriptorSet), "vkAllocateDescriptorSets");
}

// What one run creates; destroyed when the run ends, normally or by an exception.
struct RunObjects {
    const Context& s;
    std::vector<std::unique_ptr<DeviceBuffer>> buffers;
    std::vector<VkAccelerationStructureKHR> structures;
    bool submitted = false;

    explicit RunObjects(const Context& side) : s(side) {}
    ~RunObjects() {
        if (submitted) vkQueueWaitIdle(s.queue);  // a failed wait must not free memory the device still uses
        for (VkAccelerationStructureKHR as : structures) s.vk.vkDestroyAccelerationStructureKHR(s.device, as, nullptr);
    }
    RunObjects(const RunObjects&) = delete;
    RunObjects& operator=(const RunObjects&) = delete;

    DeviceBuffer& buffer(VkDeviceSize size, VkBufferUsageFlags usage) {
        buffers.push_back(std::make_unique<DeviceBuffer>(s, size, usage));
        return *buffers.back();
    }

    template <typename T>
    DeviceBuffer& storage(const std::vector<T>& data) {
        DeviceBuffer& b = buffer(data.size() * sizeof(T), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
        if (!data.empty()) std::memcpy(b.mapped, data.data(), data.size() * sizeof(T));
        return b;
    }

    // Creates a structure for the build sizes of `info` in a buffer of its own; sets info's destination.
    VkAccelerationStructureBuildSizesInfoKHR create(
        VkAccelerationStructureBuildGeometryInfoKHR& info,
        const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges) {
        std::vector<uint32_t> maxPrimitiveCounts;
        for (const auto& r : ranges) maxPrimitiveCounts.push_back(r.primitiveCount);
        VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
        s.vk.vkGetAccelerationStructureBuildSizesKHR(s.device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_DEVICE_KHR, &info,
                                                     maxPrimitiveCounts.data(), &sizes);
        const DeviceBuffer& memory =
            buffer(sizes.accelerationStructureSize,
                   VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT);
        VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
        ci.buffer = memory.buffer;
        ci.size = sizes.accelerationStructureSize;
        ci.type = info.type;
        VkAccelerationStructureKHR as = VK_NULL_HANDLE;
        check(s.vk.vkCreateAccelerationStructureKHR(s.device, &ci, nullptr, &as), "vkCreateAccelerationStructureKHR");
        structures.push_back(as);
        info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
        info.dstAccelerationStructure = as;
        return sizes;
    }
};

void barrier(VkCommandBuffer cmd, VkPipelineStageFlags src, VkAccessFlags srcAccess, VkPipelineStageFlags dst,
             VkAccessFlags dstAccess) {
    VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = srcAccess;
    mb.dstAccessMask = dstAccess;
    vkCmdPipelineBarrier(cmd, src, dst, 0, 1, &mb, 0, nullptr, 0, nullptr);
}

}  // namespace

struct LavapipeSide::Impl {
    Context context;
    Workarounds workarounds;
    size_t foldedFirstVertex = 0;
    std::vector<VkFormat> vertexFormats;
};

LavapipeSide::LavapipeSide(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

LavapipeSide::~LavapipeSide() = default;

std::unique_ptr<LavapipeSide> LavapipeSide::create(std::string* why) {
    auto impl = std::make_unique<Impl>();
    try {
        uint32_t loaderVersion = 0;
        check(vkEnumerateInstanceVersion(&loaderVersion), "vkEnumerateInstanceVersion");
        if (loaderVersion < VK_API_VERSION_1_2) {
            if (why)
                *why = "the Vulkan loader supports only Vulkan " + std::to_string(VK_API_VERSION_MAJOR(loaderVersion)) +
                       "." + std::to_string(VK_API_VERSION_MINOR(loaderVersion)) + ", 1.2 is needed";
            return nullptr;
        }
        VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
        app.pApplicationName = "vkas differential conformance";
        app.apiVersion = VK_API_VERSION_1_2;
        VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
        ici.pApplicationInfo = &app;
        check(vkCreateInstance(&ici, nullptr, &impl->context.instance), "vkCreateInstance");
        if (!impl->context.choosePhysicalDevice(why)) return nullptr;
        impl->context.createDevice();
        impl->context.createPipeline();
        // The vertex formats lavapipe accepts for acceleration-structure builds, among the 16 the spec names.
        const VkFormat candidates[] = {
            VK_FORMAT_R32G32_SFLOAT,       VK_FORMAT_R32G32B32_SFLOAT,    VK_FORMAT_R32G32B32A32_SFLOAT,
            VK_FORMAT_R16G16_SFLOAT,       VK_FORMAT_R16G16B16_SFLOAT,    VK_FORMAT_R16G16B16A16_SFLOAT,
            VK_FORMAT_R16G16_SNORM,        VK_FORMAT_R16G16B16_SNORM,     VK_FORMAT_R16G16B16A16_SNORM,
            VK_FORMAT_R8G8_SNORM,          VK_FORMAT_R8G8B8_SNORM,        VK_FORMAT_R8G8B8A8_SNORM,
            VK_FORMAT_R64G64_SFLOAT,       VK_FORMAT_R64G64B64_SFLOAT,    VK_FORMAT_R64G64B64A64_SFLOAT,
            VK_FORMAT_A2B10G10R10_UNORM_PACK32};
        for (VkFormat f : candidates) {
            VkFormatProperties props{};
            vkGetPhysicalDeviceFormatProperties(impl->context.physical, f, &props);
            if (props.bufferFeatures & VK_FORMAT_FEATURE_ACCELERATION_STRUCTURE_VERTEX_BUFFER_BIT_KHR)
                impl->vertexFormats.push_back(f);
        }
    } catch (const std::exception& e) {
        if (why) *why = e.what();
        return nullptr;
    }
    return std::unique_ptr<LavapipeSide>(new LavapipeSide(std::move(impl)));
}

std::string LavapipeSide::deviceDescription() const { return impl_->context.description; }

bool LavapipeSide::hasPositionFetch() const { return impl_->context.positionFetch; }

bool LavapipeSide::hasOpacityMicromap() const { return impl_->context.opacityMicromap; }

std::vector<VkFormat> LavapipeSide::vertexFormats() const { return impl_->vertexFormats; }

void LavapipeSide::setWorkarounds(const Workarounds& w) { impl_->workarounds = w; }

size_t LavapipeSide::foldedFirstVertexGeometries() const { return impl_->foldedFirstVertex; }

std::vector<Result> LavapipeSide::run(const Scene& scene, const std::vector<Ray>& rays) {
    const Context& s = impl_->context;
    if (scene.instances.size() > s.asProperties.maxInstanceCount)
        throw std::runtime_error("lavapipe: " + std::to_string(scene.instances.size()) +
                                 " instances exceed maxInstanceCount " +
                                 std::to_string(s.asProperties.maxInstanceCount));
    const uint64_t groups = (rays.size() + kLocalSize - 1) / kLocalSize;
    if (groups > s.maxDispatchGroups)
        throw std::runtime_error("lavapipe: " + std::to_string(rays.size()) + " rays exceed one dispatch");
    RunObjects objects(s);

    // The application data, at a 256-byte aligned address so that the blob's offsets keep their alignment.
    DeviceBuffer& blobBuffer = objects.buffer(
        scene.blob.size() + 256, VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR |
                                     VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
    const VkDeviceSize pad = (256 - blobBuffer.address % 256) % 256;
    if (!scene.blob.empty()) std::memcpy(blobBuffer.mapped + pad, scene.blob.data(), scene.blob.size());
    const VkDeviceAddress blob = blobBuffer.address + pad;

    // Structures and their build inputs; scratch regions are laid out once all sizes are known.
    const VkDeviceSize scratchAlign = s.asProperties.minAccelerationStructureScratchOffsetAlignment;
    std::vector<VkDeviceSize> scratchOffsets;
    VkDeviceSize scratchSize = 0;
    auto reserveScratch = [&](VkDeviceSize size) {
        scratchOffsets.push_back(scratchSize);
        scratchSize = alignUp(scratchSize + size, scratchAlign);
    };

    const size_t blasCount = scene.blases.size();
    std::vector<std::vector<VkAccelerationStructureGeometryKHR>> blasGeometries(blasCount);
    std::vector<std::vector<VkAccelerationStructureBuildRangeInfoKHR>> blasRanges(blasCount);
    std::vector<VkAccelerationStructureBuildGeometryInfoKHR> blasInfos(blasCount);
    std::vector<VkDeviceAddress> blasAddresses(blasCount);
    for (size_t b = 0; b < blasCount; ++b) {
        const Blas& blas = scene.blases[b];
        for (const Geometry& g : blas.geometries) {
            blasGeometries[b].push_back(vulkanGeometry(g, blob));
            blasRanges[b].push_back(g.range);
            if (impl_->workarounds.foldFirstVertex && g.type == VK_GEOMETRY_TYPE_TRIANGLES_KHR &&
                g.range.firstVertex != 0) {
                // The same vertices by the spec's fetch rules: vertexData + stride * (firstVertex + i).
                auto& t = blasGeometries[b].back().geometry.triangles;
                t.vertexData.deviceAddress += VkDeviceAddress(g.range.firstVertex) * g.triangles.vertexStride;
                t.maxVertex -= g.range.firstVertex;
                blasRanges[b].back().firstVertex = 0;
                ++impl_->foldedFirstVertex;
            }
        }
        VkAccelerationStructureBuildGeometryInfoKHR& info = blasInfos[b];
        info = {VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
        info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
        info.flags = blas.buildFlags;
        info.geometryCount = uint32_t(blasGeometries[b].size());
        info.pGeometries = blasGeometries[b].data();
        reserveScratch(objects.create(info, blasRanges[b]).buildScratchSize);
        VkAccelerationStructureDeviceAddressInfoKHR dai{
            VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
        dai.accelerationStructure = info.dstAccelerationStructure;
        blasAddresses[b] = s.vk.vkGetAccelerationStructureDeviceAddressKHR(s.device, &dai);
    }

    // At least one element so that an empty TLAS still has a valid instance address.
    DeviceBuffer& instanceBuffer = objects.buffer(64 * std::max<size_t>(scene.instances.size(), 1),
                                                  VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR |
                                                      VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT);
    for (size_t i = 0; i < scene.instances.size(); ++i) {
        const Instance& in = scene.instances[i];
        if (in.blas >= int32_t(blasCount))
            throw std::runtime_error("lavapipe: instance " + std::to_string(i) + " refers to BLAS " +
                                     std::to_string(in.blas) + " of " + std::to_string(blasCount));
        packInstance(in, in.blas < 0 ? 0 : blasAddresses[size_t(in.blas)], instanceBuffer.mapped + 64 * i);
    }
    VkAccelerationStructureGeometryKHR tlasGeometry{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    tlasGeometry.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
    tlasGeometry.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
    tlasGeometry.geometry.instances.arrayOfPointers = VK_FALSE;
    tlasGeometry.geometry.instances.data.deviceAddress = instanceBuffer.address;
    VkAccelerationStructureBuildGeometryInfoKHR tlasInfo{
        VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    tlasInfo.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
    tlasInfo.flags = scene.tlasFlags;
    tlasInfo.geometryCount = 1;
    tlasInfo.pGeometries = &tlasGeometry;
    VkAccelerationStructureBuildRangeInfoKHR tlasRange{};
    tlasRange.primitiveCount = uint32_t(scene.instances.size());
    reserveScratch(objects.create(tlasInfo, {tlasRange}).buildScratchSize);

    // One scratch buffer; its regions (and so its base) aligned to minAccelerationStructureScratchOffsetAlignment.
    DeviceBuffer& scratch = objects.buffer(
        scratchSize + scratchAlign, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT);
    const VkDeviceAddress scratchBase = alignUp(scratch.address, scratchAlign);
    for (size_t b = 0; b < blasCount; ++b) blasInfos[b].scratchData.deviceAddress = scratchBase + scratchOffsets[b];
    tlasInfo.scratchData.deviceAddress = scratchBase + scratchOffsets[blasCount];

    // Shader inputs and outputs.
    const ProceduralTables tables = makeProceduralTables(scene);
    DeviceBuffer& rayBuffer = objects.storage(rays);
    DeviceBuffer& resultBuffer = objects.buffer(rays.size() * sizeof(Result), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
    const DeviceBuffer* tableBuffers[kTableCount] = {
        &objects.storage(tables.instanceBlas), &objects.storage(tables.blasFirstGeometry),
        &objects.storage(tables.blasFlags), &objects.storage(tables.geometryFirstBox), &objects.storage(tables.boxes)};

    const VkAccelerationStructureKHR tlas = tlasInfo.dstAccelerationStructure;
    VkWriteDescriptorSetAccelerationStructureKHR asWrite{
        VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET_ACCELERATION_STRUCTURE_KHR};
    asWrite.accelerationStructureCount = 1;
    asWrite.pAccelerationStructures = &tlas;
    std::vector<VkDescriptorBufferInfo> bufferInfos = {{rayBuffer.buffer, 0, VK_WHOLE_SIZE},
                                                       {resultBuffer.buffer, 0, VK_WHOLE_SIZE}};
    for (const DeviceBuffer* t : tableBuffers) bufferInfos.push_back({t->buffer, 0, VK_WHOLE_SIZE});
    std::vector<VkWriteDescriptorSet> writes;
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, &asWrite};
    w.dstSet = s.descriptorSet;
    w.dstBinding = 0;
    w.descriptorCount = 1;
    w.descriptorType = VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR;
    writes.push_back(w);
    for (uint32_t i = 0; i < bufferInfos.size(); ++i) {
        w = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        w.dstSet = s.descriptorSet;
        w.dstBinding = 1 + i;
        w.descriptorCount = 1;
        w.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        w.pBufferInfo = &bufferInfos[i];
        writes.push_back(w);
    }
    vkUpdateDescriptorSets(s.device, uint32_t(writes.size()), writes.data(), 0, nullptr);

    // Record: BLAS builds, barrier, TLAS build, barrier, the ray program, barrier to the host.
    VkCommandBuffer cmd = s.commandBuffer;
    check(vkResetCommandBuffer(cmd, 0), "vkResetCommandBuffer");
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    check(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer");
    if (blasCount > 0) {
        std::vector<const VkAccelerationStructureBuildRangeInfoKHR*> ranges;
        for (const auto& r : blasRanges) ranges.push_back(r.data());
        s.vk.vkCmdBuildAccelerationStructuresKHR(cmd, uint32_t(blasCount), blasInfos.data(), ranges.data());
        barrier(cmd, VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR,
                VK_ACCESS_ACCELERATION_STRUCTURE_WRITE_BIT_KHR, VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR,
                VK_ACCESS_ACCELERATION_STRUCTURE_READ_BIT_KHR);
    }
    const VkAccelerationStructureBuildRangeInfoKHR* pTlasRange = &tlasRange;
    s.vk.vkCmdBuildAccelerationStructuresKHR(cmd, 1, &tlasInfo, &pTlasRange);
    barrier(cmd, VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR, VK_ACCESS_ACCELERATION_STRUCTURE_WRITE_BIT_KHR,
            VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_ACCELERATION_STRUCTURE_READ_BIT_KHR);
    if (groups > 0) {
        const uint32_t rayCount = uint32_t(rays.size());
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.pipeline);
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.pipelineLayout, 0, 1, &s.descriptorSet, 0,
                                nullptr);
        vkCmdPushConstants(cmd, s.pipelineLayout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof rayCount, &rayCount);
        vkCmdDispatch(cmd, uint32_t(groups), 1, 1);
        barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                VK_ACCESS_HOST_READ_BIT);
    }
    check(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");

    check(vkResetFences(s.device, 1, &s.fence), "vkResetFences");
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    check(vkQueueSubmit(s.queue, 1, &submit, s.fence), "vkQueueSubmit");
    objects.submitted = true;
    constexpr uint64_t kTimeoutNs = 600'000'000'000;  // a run of the test suite takes seconds
    check(vkWaitForFences(s.device, 1, &s.fence, VK_TRUE, kTimeoutNs), "vkWaitForFences");

    std::vector<Result> results(rays.size());
    if (!rays.empty()) std::memcpy(results.data(), resultBuffer.mapped, rays.size() * sizeof(Result));
    return results;
}

}  // namespace diff
