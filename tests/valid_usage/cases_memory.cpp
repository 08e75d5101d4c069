// Valid-usage cases: buffers, device memory and the device itself.
#include "harness.hpp"

#include <algorithm>
#include <cstdlib>

namespace vu {

namespace {

#define CASE(id, ...) c.push_back(Case{id, "", [](Fixture& t, const vt::Commands& vk, VkDevice dev) __VA_ARGS__})
#define CASE_V(id, variant, ...) \
    c.push_back(Case{id, variant, [](Fixture& t, const vt::Commands& vk, VkDevice dev) __VA_ARGS__})
#define CASE_ALSO(id, also, ...) \
    c.push_back(Case{id, "", [](Fixture& t, const vt::Commands& vk, VkDevice dev) __VA_ARGS__, also})

VkBufferCreateInfo bufferInfo() {
    VkBufferCreateInfo ci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    ci.size = 1024;
    ci.usage = vt::kAsBufferUsage;
    ci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    return ci;
}

// Creates a buffer with a broken create info; the handle must stay untouched.
void createBuffer(Fixture& t, const vt::Commands& vk, VkDevice dev, const VkBufferCreateInfo& ci) {
    static VkBuffer out;
    out = t.bogus<VkBuffer>();
    t.watch(&out, sizeof out);
    t.call([&] { return R(vk.vkCreateBuffer(dev, &ci, nullptr, &out)); });
}

VkMemoryAllocateInfo memoryInfo(const void* pNext = nullptr) {
    return VkMemoryAllocateInfo{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, pNext, 4096, 0};
}

void allocate(Fixture& t, const vt::Commands& vk, VkDevice dev, const VkMemoryAllocateInfo& ai) {
    static VkDeviceMemory out;
    out = t.bogus<VkDeviceMemory>();
    t.watch(&out, sizeof out);
    t.call([&] { return R(vk.vkAllocateMemory(dev, &ai, nullptr, &out)); });
}

VkBuffer newBuffer(Fixture& t, VkBufferUsageFlags usage = vt::kAsBufferUsage, VkDeviceSize size = 1024) {
    return t.createBuffer(size, usage, /*bind=*/false)->buffer;
}

VkDeviceMemory newMemory(Fixture& t, VkDeviceSize size = 4096, bool deviceAddress = true) {
    VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
    flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
    VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, deviceAddress ? &flags : nullptr, size, 0};
    VkDeviceMemory memory = VK_NULL_HANDLE;
    EXPECT_EQ(t.vk.vkAllocateMemory(t.device, &ai, nullptr, &memory), VK_SUCCESS);
    return memory;
}

}  // namespace

void addMemoryCases(std::vector<Case>& c) {
    // ---- vkCreateBuffer / VkBufferCreateInfo ------------------------------------------------------------------
    CASE("VUID-vkCreateBuffer-device-parameter", {
        auto ci = bufferInfo();
        VkBuffer out = VK_NULL_HANDLE;
        t.call([&] { return R(vk.vkCreateBuffer(t.bogus<VkDevice>(), &ci, nullptr, &out)); });
        EXPECT_EQ(out, VK_NULL_HANDLE);
        (void)dev;
    });
    CASE("VUID-vkCreateBuffer-pCreateInfo-parameter", {
        VkBuffer out = VK_NULL_HANDLE;
        t.call([&] { return R(vk.vkCreateBuffer(dev, nullptr, nullptr, &out)); });
        EXPECT_EQ(out, VK_NULL_HANDLE);
    });
    CASE("VUID-vkCreateBuffer-pBuffer-parameter", {
        auto ci = bufferInfo();
        t.call([&] { return R(vk.vkCreateBuffer(dev, &ci, nullptr, nullptr)); });
    });
    CASE("VUID-VkBufferCreateInfo-sType-sType", {
        auto ci = bufferInfo();
        ci.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
        createBuffer(t, vk, dev, ci);
    });
    CASE("VUID-VkBufferCreateInfo-pNext-pNext", {
        auto ci = bufferInfo();
        VkMemoryAllocateFlagsInfo unrelated{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
        ci.pNext = &unrelated;
        createBuffer(t, vk, dev, ci);
    });
    CASE("VUID-VkBufferCreateInfo-size-00912", {
        auto ci = bufferInfo();
        ci.size = 0;
        createBuffer(t, vk, dev, ci);
    });
    CASE("VUID-VkBufferCreateInfo-flags-parameter", {
        auto ci = bufferInfo();
        ci.flags = 0x40000000u;
        createBuffer(t, vk, dev, ci);
    });
    CASE("VUID-VkBufferCreateInfo-usage-parameter", {
        auto ci = bufferInfo();
        ci.usage |= 0x40000000u;
        createBuffer(t, vk, dev, ci);
    });
    CASE("VUID-VkBufferCreateInfo-usage-requiredbitmask", {
        auto ci = bufferInfo();
        ci.usage = 0;
        createBuffer(t, vk, dev, ci);
    });
    CASE("VUID-VkBufferCreateInfo-sharingMode-parameter", {
        auto ci = bufferInfo();
        ci.sharingMode = VkSharingMode(7);
        createBuffer(t, vk, dev, ci);
    });
    CASE("VUID-VkBufferCreateInfo-sharingMode-00913", {
        auto ci = bufferInfo();
        ci.sharingMode = VK_SHARING_MODE_CONCURRENT;
        ci.queueFamilyIndexCount = 2;
        ci.pQueueFamilyIndices = nullptr;
        createBuffer(t, vk, dev, ci);
    });
    CASE("VUID-VkBufferCreateInfo-sharingMode-00914", {
        auto ci = bufferInfo();
        static const uint32_t families[] = {0};
        ci.sharingMode = VK_SHARING_MODE_CONCURRENT;
        ci.queueFamilyIndexCount = 1;
        ci.pQueueFamilyIndices = families;
        createBuffer(t, vk, dev, ci);
    });
    CASE("VUID-VkBufferCreateInfo-sharingMode-01419", {
        auto ci = bufferInfo();
        static const uint32_t families[] = {0, 1};  // vkas has one queue family
        ci.sharingMode = VK_SHARING_MODE_CONCURRENT;
        ci.queueFamilyIndexCount = 2;
        ci.pQueueFamilyIndices = families;
        createBuffer(t, vk, dev, ci);
    });
    CASE("VUID-VkBufferCreateInfo-flags-00915", {
        auto ci = bufferInfo();
        ci.flags = VK_BUFFER_CREATE_SPARSE_BINDING_BIT;
        createBuffer(t, vk, dev, ci);
    });
    CASE_ALSO("VUID-VkBufferCreateInfo-flags-00916", {"VUID-VkBufferCreateInfo-flags-00915"}, {
        auto ci = bufferInfo();
        ci.flags = VK_BUFFER_CREATE_SPARSE_BINDING_BIT | VK_BUFFER_CREATE_SPARSE_RESIDENCY_BIT;
        createBuffer(t, vk, dev, ci);
    });
    CASE_ALSO("VUID-VkBufferCreateInfo-flags-00917", {"VUID-VkBufferCreateInfo-flags-00915"}, {
        auto ci = bufferInfo();
        ci.flags = VK_BUFFER_CREATE_SPARSE_BINDING_BIT | VK_BUFFER_CREATE_SPARSE_ALIASED_BIT;
        createBuffer(t, vk, dev, ci);
    });
    CASE_ALSO("VUID-VkBufferCreateInfo-flags-00918", {"VUID-VkBufferCreateInfo-flags-00916"}, {
        auto ci = bufferInfo();
        ci.flags = VK_BUFFER_CREATE_SPARSE_RESIDENCY_BIT;
        createBuffer(t, vk, dev, ci);
    });
    CASE("VUID-VkBufferCreateInfo-flags-01887", {
        auto ci = bufferInfo();
        ci.flags = VK_BUFFER_CREATE_PROTECTED_BIT;
        createBuffer(t, vk, dev, ci);
    });
    CASE("VUID-VkBufferCreateInfo-flags-06549", {
        auto ci = bufferInfo();
        ci.flags = VK_BUFFER_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT;
        createBuffer(t, vk, dev, ci);
    });

    // ---- vkDestroyBuffer, vkGetBufferMemoryRequirements ---------------------------------------------------------
    CASE("VUID-vkDestroyBuffer-device-parameter", {
        VkBuffer b = newBuffer(t);
        t.call([&] {
            vk.vkDestroyBuffer(t.bogus<VkDevice>(), b, nullptr);
            return V();
        });
        (void)dev;
    });
    CASE("VUID-vkDestroyBuffer-buffer-parameter", {
        t.call([&] {
            vk.vkDestroyBuffer(dev, t.bogus<VkBuffer>(), nullptr);
            return V();
        });
    });
    CASE("VUID-vkDestroyBuffer-buffer-parent", {
        VkBuffer b = t.otherBuffer(false);
        t.call([&] {
            vk.vkDestroyBuffer(dev, b, nullptr);
            return V();
        });
        t.otherVk.vkDestroyBuffer(t.other, b, nullptr);  // still alive
    });
    CASE("VUID-vkGetBufferMemoryRequirements-device-parameter", {
        VkBuffer b = newBuffer(t);
        static VkMemoryRequirements req;
        std::memset(&req, 0xAA, sizeof req);
        t.watch(&req, sizeof req);
        t.call([&] {
            vk.vkGetBufferMemoryRequirements(t.bogus<VkDevice>(), b, &req);
            return V();
        });
        (void)dev;
    });
    CASE("VUID-vkGetBufferMemoryRequirements-buffer-parameter", {
        static VkMemoryRequirements req;
        std::memset(&req, 0xAA, sizeof req);
        t.watch(&req, sizeof req);
        t.call([&] {
            vk.vkGetBufferMemoryRequirements(dev, t.bogus<VkBuffer>(), &req);
            return V();
        });
    });
    CASE("VUID-vkGetBufferMemoryRequirements-buffer-parent", {
        VkBuffer b = t.otherBuffer(false);
        static VkMemoryRequirements req;
        std::memset(&req, 0xAA, sizeof req);
        t.watch(&req, sizeof req);
        t.call([&] {
            vk.vkGetBufferMemoryRequirements(dev, b, &req);
            return V();
        });
    });
    CASE("VUID-vkGetBufferMemoryRequirements-pMemoryRequirements-parameter", {
        VkBuffer b = newBuffer(t);
        t.call([&] {
            vk.vkGetBufferMemoryRequirements(dev, b, nullptr);
            return V();
        });
    });

    // ---- vkAllocateMemory / VkMemoryAllocateInfo / VkMemoryAllocateFlagsInfo ------------------------------------
    CASE("VUID-vkAllocateMemory-device-parameter", {
        auto ai = memoryInfo();
        VkDeviceMemory out = VK_NULL_HANDLE;
        t.call([&] { return R(vk.vkAllocateMemory(t.bogus<VkDevice>(), &ai, nullptr, &out)); });
        EXPECT_EQ(out, VK_NULL_HANDLE);
        (void)dev;
    });
    CASE("VUID-vkAllocateMemory-pAllocateInfo-parameter", {
        VkDeviceMemory out = VK_NULL_HANDLE;
        t.call([&] { return R(vk.vkAllocateMemory(dev, nullptr, nullptr, &out)); });
        EXPECT_EQ(out, VK_NULL_HANDLE);
    });
    CASE("VUID-vkAllocateMemory-pMemory-parameter", {
        auto ai = memoryInfo();
        t.call([&] { return R(vk.vkAllocateMemory(dev, &ai, nullptr, nullptr)); });
    });
    CASE("VUID-vkAllocateMemory-pAllocateInfo-01714", {
        auto ai = memoryInfo();
        ai.memoryTypeIndex = 1;
        allocate(t, vk, dev, ai);
    });
    CASE("VUID-VkMemoryAllocateInfo-sType-sType", {
        auto ai = memoryInfo();
        ai.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
        allocate(t, vk, dev, ai);
    });
    CASE("VUID-VkMemoryAllocateInfo-pNext-pNext", {
        VkBufferDeviceAddressInfo unrelated{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        allocate(t, vk, dev, memoryInfo(&unrelated));
    });
    CASE("VUID-VkMemoryAllocateInfo-sType-unique", {
        static VkMemoryAllocateFlagsInfo second{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
        static VkMemoryAllocateFlagsInfo first{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO, &second};
        allocate(t, vk, dev, memoryInfo(&first));
    });
    CASE("VUID-VkMemoryAllocateInfo-allocationSize-07897", {
        auto ai = memoryInfo();
        ai.allocationSize = 0;
        allocate(t, vk, dev, ai);
    });
    CASE("VUID-VkMemoryAllocateInfo-flags-03330", {
        static VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
        flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT | VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT;
        allocate(t, vk, dev, memoryInfo(&flags));
    });
    CASE("VUID-VkMemoryAllocateFlagsInfo-flags-parameter", {
        static VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
        flags.flags = 0x100u;
        allocate(t, vk, dev, memoryInfo(&flags));
    });
    CASE("VUID-VkMemoryAllocateFlagsInfo-deviceMask-00675", {
        static VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
        flags.flags = VK_MEMORY_ALLOCATE_DEVICE_MASK_BIT;
        flags.deviceMask = 0x2;  // vkas is one physical device: only bit 0 names one
        allocate(t, vk, dev, memoryInfo(&flags));
    });
    CASE("VUID-VkMemoryAllocateFlagsInfo-deviceMask-00676", {
        static VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
        flags.flags = VK_MEMORY_ALLOCATE_DEVICE_MASK_BIT;
        flags.deviceMask = 0;
        allocate(t, vk, dev, memoryInfo(&flags));
    });

    // ---- vkFreeMemory, vkBindBufferMemory ---------------------------------------------------------------------
    CASE("VUID-vkFreeMemory-device-parameter", {
        VkDeviceMemory m = newMemory(t);
        t.call([&] {
            vk.vkFreeMemory(t.bogus<VkDevice>(), m, nullptr);
            return V();
        });
        vk.vkFreeMemory(dev, m, nullptr);
    });
    CASE("VUID-vkFreeMemory-memory-parameter", {
        t.call([&] {
            vk.vkFreeMemory(dev, t.bogus<VkDeviceMemory>(), nullptr);
            return V();
        });
    });
    CASE("VUID-vkFreeMemory-memory-parent", {
        VkDeviceMemory m = t.otherMemory();
        t.call([&] {
            vk.vkFreeMemory(dev, m, nullptr);
            return V();
        });
    });
    CASE("VUID-vkBindBufferMemory-device-parameter", {
        VkBuffer b = newBuffer(t);
        VkDeviceMemory m = newMemory(t);
        t.call([&] { return R(vk.vkBindBufferMemory(t.bogus<VkDevice>(), b, m, 0)); });
        (void)dev;
    });
    CASE("VUID-vkBindBufferMemory-buffer-parameter", {
        VkDeviceMemory m = newMemory(t);
        t.call([&] { return R(vk.vkBindBufferMemory(dev, t.bogus<VkBuffer>(), m, 0)); });
    });
    CASE("VUID-vkBindBufferMemory-memory-parameter", {
        VkBuffer b = newBuffer(t);
        t.call([&] { return R(vk.vkBindBufferMemory(dev, b, t.bogus<VkDeviceMemory>(), 0)); });
    });
    CASE("VUID-vkBindBufferMemory-buffer-parent", {
        VkBuffer b = t.otherBuffer(false);
        VkDeviceMemory m = newMemory(t);
        t.call([&] { return R(vk.vkBindBufferMemory(dev, b, m, 0)); });
    });
    CASE("VUID-vkBindBufferMemory-memory-parent", {
        VkBuffer b = newBuffer(t);
        VkDeviceMemory m = t.otherMemory();
        t.call([&] { return R(vk.vkBindBufferMemory(dev, b, m, 0)); });
    });
    CASE("VUID-vkBindBufferMemory-buffer-07459", {
        vt::HostBuffer* bound = t.createBuffer(1024);
        VkDeviceMemory m = newMemory(t);
        t.call([&] { return R(vk.vkBindBufferMemory(dev, bound->buffer, m, 0)); });
    });
    CASE("VUID-vkBindBufferMemory-memoryOffset-01031", {
        VkBuffer b = newBuffer(t);
        VkDeviceMemory m = newMemory(t, 4096);
        t.call([&] { return R(vk.vkBindBufferMemory(dev, b, m, 4096)); });
    });
    CASE("VUID-vkBindBufferMemory-memoryOffset-01036", {
        VkBuffer b = newBuffer(t);
        VkDeviceMemory m = newMemory(t, 4096);
        t.call([&] { return R(vk.vkBindBufferMemory(dev, b, m, 16)); });
    });
    CASE("VUID-vkBindBufferMemory-size-01037", {
        VkBuffer b = newBuffer(t, vt::kAsBufferUsage, 8192);
        VkDeviceMemory m = newMemory(t, 4096);
        t.call([&] { return R(vk.vkBindBufferMemory(dev, b, m, 0)); });
    });
    CASE("VUID-vkBindBufferMemory-bufferDeviceAddress-03339", {
        VkBuffer b = newBuffer(t);  // SHADER_DEVICE_ADDRESS usage
        VkDeviceMemory m = newMemory(t, 4096, /*deviceAddress=*/false);
        t.call([&] { return R(vk.vkBindBufferMemory(dev, b, m, 0)); });
    });

    // ---- vkMapMemory, vkUnmapMemory -------------------------------------------------------------------------------
    CASE("VUID-vkMapMemory-device-parameter", {
        VkDeviceMemory m = newMemory(t);
        void* p = &t;
        t.call([&] { return R(vk.vkMapMemory(t.bogus<VkDevice>(), m, 0, VK_WHOLE_SIZE, 0, &p)); });
        EXPECT_EQ(p, &t);
        (void)dev;
    });
    CASE("VUID-vkMapMemory-memory-parameter", {
        void* p = &t;
        t.call([&] { return R(vk.vkMapMemory(dev, t.bogus<VkDeviceMemory>(), 0, VK_WHOLE_SIZE, 0, &p)); });
        EXPECT_EQ(p, &t);
    });
    CASE("VUID-vkMapMemory-memory-parent", {
        VkDeviceMemory m = t.otherMemory();
        void* p = &t;
        t.call([&] { return R(vk.vkMapMemory(dev, m, 0, VK_WHOLE_SIZE, 0, &p)); });
        EXPECT_EQ(p, &t);
    });
    CASE("VUID-vkMapMemory-memory-00678", {
        vt::HostBuffer* mapped = t.createBuffer(1024);
        void* p = &t;
        t.call([&] { return R(vk.vkMapMemory(dev, mapped->memory, 0, VK_WHOLE_SIZE, 0, &p)); });
        EXPECT_EQ(p, &t);
    });
    CASE("VUID-vkMapMemory-offset-00679", {
        VkDeviceMemory m = newMemory(t, 4096);
        void* p = &t;
        t.call([&] { return R(vk.vkMapMemory(dev, m, 4096, VK_WHOLE_SIZE, 0, &p)); });
        EXPECT_EQ(p, &t);
    });
    CASE("VUID-vkMapMemory-size-00680", {
        VkDeviceMemory m = newMemory(t, 4096);
        void* p = &t;
        t.call([&] { return R(vk.vkMapMemory(dev, m, 0, 0, 0, &p)); });
        EXPECT_EQ(p, &t);
    });
    CASE("VUID-vkMapMemory-size-00681", {
        VkDeviceMemory m = newMemory(t, 4096);
        void* p = &t;
        t.call([&] { return R(vk.vkMapMemory(dev, m, 1024, 4096, 0, &p)); });
        EXPECT_EQ(p, &t);
    });
    CASE("VUID-vkMapMemory-flags-zerobitmask", {
        VkDeviceMemory m = newMemory(t, 4096);
        void* p = &t;
        t.call([&] { return R(vk.vkMapMemory(dev, m, 0, VK_WHOLE_SIZE, 1, &p)); });
        EXPECT_EQ(p, &t);
    });
    CASE("VUID-vkMapMemory-ppData-parameter", {
        VkDeviceMemory m = newMemory(t, 4096);
        t.call([&] { return R(vk.vkMapMemory(dev, m, 0, VK_WHOLE_SIZE, 0, nullptr)); });
    });
    CASE("VUID-vkUnmapMemory-device-parameter", {
        vt::HostBuffer* mapped = t.createBuffer(1024);
        t.call([&] {
            vk.vkUnmapMemory(t.bogus<VkDevice>(), mapped->memory);
            return V();
        });
        (void)dev;
    });
    CASE("VUID-vkUnmapMemory-memory-parameter", {
        t.call([&] {
            vk.vkUnmapMemory(dev, t.bogus<VkDeviceMemory>());
            return V();
        });
    });
    CASE("VUID-vkUnmapMemory-memory-parent", {
        VkDeviceMemory m = t.otherMemory();
        t.call([&] {
            vk.vkUnmapMemory(dev, m);
            return V();
        });
    });
    CASE("VUID-vkUnmapMemory-memory-00689", {
        VkDeviceMemory m = newMemory(t, 4096);
        t.call([&] {
            vk.vkUnmapMemory(dev, m);
            return V();
        });
    });

    // ---- vkGetBufferDeviceAddress -------------------------------------------------------------------------------
    CASE("VUID-vkGetBufferDeviceAddress-device-parameter", {
        vt::HostBuffer* b = t.createBuffer(1024);
        VkBufferDeviceAddressInfo info{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO, nullptr, b->buffer};
        t.call([&] {
            EXPECT_EQ(vk.vkGetBufferDeviceAddress(t.bogus<VkDevice>(), &info), 0u);
            return V();
        });
        (void)dev;
    });
    CASE("VUID-vkGetBufferDeviceAddress-pInfo-parameter", {
        t.call([&] {
            EXPECT_EQ(vk.vkGetBufferDeviceAddress(dev, nullptr), 0u);
            return V();
        });
    });
    CASE("VUID-VkBufferDeviceAddressInfo-sType-sType", {
        vt::HostBuffer* b = t.createBuffer(1024);
        VkBufferDeviceAddressInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, nullptr, b->buffer};
        t.call([&] {
            EXPECT_EQ(vk.vkGetBufferDeviceAddress(dev, &info), 0u);
            return V();
        });
    });
    CASE("VUID-VkBufferDeviceAddressInfo-pNext-pNext", {
        vt::HostBuffer* b = t.createBuffer(1024);
        VkMemoryAllocateFlagsInfo unrelated{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
        VkBufferDeviceAddressInfo info{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO, &unrelated, b->buffer};
        t.call([&] {
            EXPECT_EQ(vk.vkGetBufferDeviceAddress(dev, &info), 0u);
            return V();
        });
    });
    CASE("VUID-VkBufferDeviceAddressInfo-buffer-parameter", {
        VkBufferDeviceAddressInfo info{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO, nullptr, t.bogus<VkBuffer>()};
        t.call([&] {
            EXPECT_EQ(vk.vkGetBufferDeviceAddress(dev, &info), 0u);
            return V();
        });
    });
    CASE("VUID-VkBufferDeviceAddressInfo-buffer-02600", {
        VkBufferDeviceAddressInfo info{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO, nullptr, newBuffer(t)};
        t.call([&] {
            EXPECT_EQ(vk.vkGetBufferDeviceAddress(dev, &info), 0u);
            return V();
        });
    });
    CASE("VUID-VkBufferDeviceAddressInfo-buffer-02601", {
        vt::HostBuffer* b = t.createBuffer(1024, VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR);
        VkBufferDeviceAddressInfo info{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO, nullptr, b->buffer};
        t.call([&] {
            EXPECT_EQ(vk.vkGetBufferDeviceAddress(dev, &info), 0u);
            return V();
        });
    });

    // ---- vkDestroyDevice ------------------------------------------------------------------------------------------
    CASE("VUID-vkDestroyDevice-device-parameter", {
        t.call([&] {
            t.deferred.destroyDevice(t.bogus<VkDevice>(), nullptr);
            return V();
        });
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkDestroyDevice-device-00379", {
        // A device created with callbacks, destroyed without: reported, nothing destroyed.
        static VkAllocationCallbacks callbacks = [] {
            VkAllocationCallbacks c{};
            c.pfnAllocation = [](void*, size_t size, size_t alignment, VkSystemAllocationScope) -> void* {
                void* p = nullptr;
                return posix_memalign(&p, std::max<size_t>(alignment, sizeof(void*)), size) == 0 ? p : nullptr;
            };
            c.pfnReallocation = [](void*, void*, size_t, size_t, VkSystemAllocationScope) -> void* { return nullptr; };
            c.pfnFree = [](void*, void* p) { std::free(p); };
            return c;
        }();
        VkasDeviceCreateInfo ci{};
        ci.pfnMessenger = &vt::VkasTest::messenger;
        ci.pMessengerUserData = static_cast<vt::VkasTest*>(&t);
        VkDevice withCallbacks = VK_NULL_HANDLE;
        ASSERT_EQ(vkasCreateDeviceWithAllocator(&ci, &callbacks, &withCallbacks), VK_SUCCESS);
        t.call([&] {
            t.deferred.destroyDevice(withCallbacks, nullptr);
            return V();
        });
        EXPECT_NE(vkasGetDeviceProcAddr(withCallbacks, "vkDestroyDevice"), nullptr) << "the device was destroyed";
        vkasDestroyDevice(withCallbacks);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkDestroyDevice-device-00380", {
        VkAllocationCallbacks callbacks{};
        t.call([&] {
            t.deferred.destroyDevice(t.other, &callbacks);
            return V();
        });
        EXPECT_NE(vkasGetDeviceProcAddr(t.other, "vkDestroyDevice"), nullptr) << "the device was destroyed";
        (void)vk;
        (void)dev;
    });
    c.push_back(Case{"VUID-vkDestroyDevice-device-05137", "",
                     [](Fixture& t, const vt::Commands&, VkDevice) {
                         t.otherBuffer(false);
                         t.call([&] {
                             t.deferred.destroyDevice(t.other, nullptr);  // frees the buffer and reports it
                             return V();
                         });
                         t.other = VK_NULL_HANDLE;
                     },
                     {},
                     /*hasEffect=*/true});
}

}  // namespace vu
