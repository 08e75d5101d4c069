// The application's allocator (issue "The application's allocator"): the device is created with
// vkasCreateDeviceWithAllocator and recording VkAllocationCallbacks; the objects and deferred operations of some runs
// get callbacks of their own. For every command:
//   - every host allocation vkas makes goes through the callbacks: none through operator new (the allocation hook of
//     support/alloc_failure.hpp, linked into this executable, counts them), with a valid power-of-two alignment
//     that the returned memory honours, and pfnFree only ever given what pfnAllocation returned;
//   - with the scope the spec assigns: COMMAND for what lasts only for the command (all freed when it returns),
//     OBJECT for an object's memory and a deferred operation's state (freed when the object is destroyed), DEVICE
//     for the device's own (freed by vkasDestroyDevice);
//   - failing allocation k for k = 0, 1, 2, ... (stepped) returns VK_ERROR_OUT_OF_HOST_MEMORY with nothing leaked
//     (per scope, and through operator new) and nothing half-written: the destination holds what it held before,
//     or is marked unconstructed (no structure magic); then the command succeeds with the reference result.
// And: a validation message far longer than any fixed buffer arrives whole, through the device's allocator.
#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <mutex>
#include <thread>

#include "alloc_failure.hpp"
#include "api/device.hpp"
#include "api/validate/validator.hpp"
#include "engine/format/layout.hpp"
#include "meshes.hpp"
#include "vkas_test.hpp"

using namespace vt;

namespace {

constexpr uint64_t kNever = uint64_t(1) << 62;  // alloc::armFailure(kNever): count operator new, fail none
constexpr uint32_t kMaxFailingRuns = 40;         // per sweep: k is stepped to stay under this
constexpr int kScopes = 5;                       // VK_SYSTEM_ALLOCATION_SCOPE_COMMAND .. INSTANCE
constexpr uint32_t bit(VkSystemAllocationScope s) { return 1u << uint32_t(s); }
constexpr uint32_t kCommand = bit(VK_SYSTEM_ALLOCATION_SCOPE_COMMAND);
constexpr uint32_t kObject = bit(VK_SYSTEM_ALLOCATION_SCOPE_OBJECT);
constexpr uint32_t kDevice = bit(VK_SYSTEM_ALLOCATION_SCOPE_DEVICE);

// VkAllocationCallbacks that record every allocation (a header before each block, so the recorder itself never
// allocates through operator new) and fail the allocation numbered failAt.
struct Recorder {
    struct Header {
        uint64_t magic;
        uint64_t size;
        uint64_t offset;  // from the malloc'ed base to the block
        uint32_t scope;
        uint32_t alignment;
    };
    static constexpr uint64_t kMagic = 0x5245434F52444552ull;

    std::atomic<int64_t> calls{0};
    std::atomic<int64_t> failAt{-1};
    std::atomic<bool> injected{false};
    std::atomic<int64_t> live[kScopes]{};     // blocks not freed yet, per scope
    std::atomic<int64_t> made[kScopes]{};     // blocks allocated so far, per scope
    std::atomic<int64_t> badAlignment{0};     // requested alignment 0 or not a power of two, or not honoured
    std::atomic<int64_t> badFree{0};          // pfnFree of something pfnAllocation did not return
    std::atomic<int64_t> badScope{0};         // a scope outside the enum
    std::atomic<int64_t> reallocations{0};    // vkas never calls pfnReallocation
    std::atomic<uint64_t> largest{0};

    VkAllocationCallbacks callbacks() {
        VkAllocationCallbacks c{};
        c.pUserData = this;
        c.pfnAllocation = &allocation;
        c.pfnReallocation = &reallocation;
        c.pfnFree = &release;
        return c;
    }
    int64_t liveTotal() const {
        int64_t n = 0;
        for (const auto& l : live) n += l.load();
        return n;
    }
    struct Snapshot {
        int64_t live[kScopes], made[kScopes], calls;
    };
    Snapshot snapshot() const {
        Snapshot s{};
        for (int i = 0; i < kScopes; ++i) s.live[i] = live[i].load(), s.made[i] = made[i].load();
        s.calls = calls.load();
        return s;
    }
    // The scopes (bit mask) of the allocations made since `s`.
    uint32_t scopesSince(const Snapshot& s) const {
        uint32_t mask = 0;
        for (int i = 0; i < kScopes; ++i)
            if (made[i].load() != s.made[i]) mask |= 1u << i;
        return mask;
    }
    // Whether every scope has as many live blocks as at `s`.
    bool sameLive(const Snapshot& s) const {
        for (int i = 0; i < kScopes; ++i)
            if (live[i].load() != s.live[i]) return false;
        return true;
    }
    bool clean() const { return badAlignment == 0 && badFree == 0 && badScope == 0 && reallocations == 0; }

    static void* VKAPI_PTR allocation(void* user, size_t size, size_t alignment, VkSystemAllocationScope scope) {
        auto* self = static_cast<Recorder*>(user);
        const int64_t index = self->calls.fetch_add(1);
        if (index == self->failAt.load()) {
            self->injected = true;
            return nullptr;
        }
        if (uint32_t(scope) >= uint32_t(kScopes)) ++self->badScope;
        if (alignment == 0 || (alignment & (alignment - 1)) != 0) {
            ++self->badAlignment;
            alignment = 16;
        }
        const size_t a = std::max<size_t>(alignment, 16);
        const size_t offset = (sizeof(Header) + a - 1) / a * a;
        void* base = nullptr;
        if (posix_memalign(&base, a, offset + size) != 0) return nullptr;
        auto* p = static_cast<std::byte*>(base) + offset;
        if (reinterpret_cast<uintptr_t>(p) % alignment != 0) ++self->badAlignment;
        Header h{kMagic, size, offset, uint32_t(scope), uint32_t(alignment)};
        std::memcpy(p - sizeof(Header), &h, sizeof h);
        ++self->live[scope % kScopes];
        ++self->made[scope % kScopes];
        uint64_t was = self->largest.load();
        while (size > was && !self->largest.compare_exchange_weak(was, size)) {
        }
        return p;
    }
    static void* VKAPI_PTR reallocation(void* user, void*, size_t, size_t, VkSystemAllocationScope) {
        ++static_cast<Recorder*>(user)->reallocations;
        return nullptr;
    }
    static void VKAPI_PTR release(void* user, void* p) {
        auto* self = static_cast<Recorder*>(user);
        if (!p) return;
        Header h;
        std::memcpy(&h, static_cast<std::byte*>(p) - sizeof(Header), sizeof h);
        if (h.magic != kMagic) {
            ++self->badFree;
            return;
        }
        h.magic = 0;
        std::memcpy(static_cast<std::byte*>(p) - sizeof(Header), &h, sizeof h);
        --self->live[h.scope % kScopes];
        std::free(static_cast<std::byte*>(p) - h.offset);
    }
};

uint64_t usedSize(const AccelStruct* as) {
    uint64_t used;
    std::memcpy(&used, as->data() + 16, sizeof used);
    return used;
}
std::vector<uint8_t> structureBytes(const AccelStruct* as) {
    return std::vector<uint8_t>(as->data(), as->data() + std::min<uint64_t>(usedSize(as), as->size));
}
std::vector<uint8_t> wholeBlock(const AccelStruct* as) { return std::vector<uint8_t>(as->data(), as->data() + as->size); }
// The same into `out` without allocating once `out` has the capacity (inside a counted call).
void keepBlock(std::vector<uint8_t>& out, const AccelStruct* as) {
    if (out.capacity() < as->size) out.reserve(as->size);
    out.assign(as->data(), as->data() + as->size);
}
uint32_t magicOf(const AccelStruct* as) {
    uint32_t magic;
    std::memcpy(&magic, as->data() + offsetof(vkas::format::Header, magic), sizeof magic);
    return magic;
}

// Threads that join a deferred operation on request, started before anything is counted (see test_out_of_memory).
class JoinCrew {
  public:
    JoinCrew(uint32_t helpers, PFN_vkDeferredOperationJoinKHR join, VkDevice device) : join_(join), device_(device) {
        for (uint32_t i = 0; i < helpers; ++i) threads_.emplace_back([this] { loop(); });
    }
    ~JoinCrew() {
        {
            std::lock_guard lock(mutex_);
            stop_ = true;
        }
        wake_.notify_all();
        for (auto& t : threads_) t.join();
    }
    // Joins `op` on this thread and every helper until each is not IDLE; false when a join returned anything but
    // SUCCESS or DONE, or none returned SUCCESS.
    bool joinAll(VkDeferredOperationKHR op) {
        {
            std::lock_guard lock(mutex_);
            op_ = op;
            ++generation_;
            busy_ = uint32_t(threads_.size());
            successes_ = bad_ = 0;
        }
        wake_.notify_all();
        record(joinUntilDone(op));
        std::unique_lock lock(mutex_);
        done_.wait(lock, [&] { return busy_ == 0; });
        return successes_ >= 1 && bad_ == 0;
    }

  private:
    VkResult joinUntilDone(VkDeferredOperationKHR op) {
        VkResult r;
        while ((r = join_(device_, op)) == VK_THREAD_IDLE_KHR) std::this_thread::yield();
        return r;
    }
    void record(VkResult r) {
        std::lock_guard lock(mutex_);
        successes_ += r == VK_SUCCESS;
        bad_ += r != VK_SUCCESS && r != VK_THREAD_DONE_KHR;
    }
    void loop() {
        uint64_t seen = 0;
        for (;;) {
            VkDeferredOperationKHR op;
            {
                std::unique_lock lock(mutex_);
                wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
                if (stop_) return;
                seen = generation_;
                op = op_;
            }
            const VkResult r = joinUntilDone(op);
            std::lock_guard lock(mutex_);
            successes_ += r == VK_SUCCESS;
            bad_ += r != VK_SUCCESS && r != VK_THREAD_DONE_KHR;
            if (--busy_ == 0) done_.notify_all();
        }
    }

    PFN_vkDeferredOperationJoinKHR join_;
    VkDevice device_;
    std::vector<std::thread> threads_;
    std::mutex mutex_;
    std::condition_variable wake_, done_;
    VkDeferredOperationKHR op_ = VK_NULL_HANDLE;
    uint64_t generation_ = 0;
    uint32_t busy_ = 0, successes_ = 0, bad_ = 0;
    bool stop_ = false;
};

}  // namespace

class allocation_callbacks : public VkasTest {
  protected:
    const VkAllocationCallbacks* deviceAllocator() override {
        deviceCallbacks_ = deviceRecorder.callbacks();
        return &deviceCallbacks_;
    }

    void SetUp() override {
        VkasTest::SetUp();
        ASSERT_NE(device, VK_NULL_HANDLE);
#define LOAD(name) name = reinterpret_cast<PFN_##name>(vkasGetDeviceProcAddr(device, #name)); ASSERT_NE(name, nullptr);
        LOAD(vkCreateDeferredOperationKHR)
        LOAD(vkDestroyDeferredOperationKHR)
        LOAD(vkGetDeferredOperationResultKHR)
        LOAD(vkDeferredOperationJoinKHR)
        LOAD(vkCreateMicromapEXT)
        LOAD(vkDestroyMicromapEXT)
        LOAD(vkGetMicromapBuildSizesEXT)
        LOAD(vkBuildMicromapsEXT)
#undef LOAD
        opCallbacks = opRecorder.callbacks();
        // Warm-up: the device's live set grows to its working size, the worker threads of vkasTraceRays start (a
        // thread's own state is not host memory vkas can route: docs/API.md "Host memory").
        std::vector<VkBuffer> buffers(256);
        VkBufferCreateInfo ci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        ci.size = 256;
        ci.usage = kAsBufferUsage;
        for (auto& b : buffers) ASSERT_EQ(vk.vkCreateBuffer(device, &ci, nullptr, &b), VK_SUCCESS);
        for (auto& b : buffers) vk.vkDestroyBuffer(device, b, nullptr);
        ASSERT_EQ(vkasTraceRays(device, VK_NULL_HANDLE, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF, 0, nullptr, nullptr),
                  VK_SUCCESS);
    }

    void TearDown() override {
        VkasTest::TearDown();  // vkasDestroyDevice: everything the device's callbacks gave must be back
        EXPECT_EQ(deviceRecorder.liveTotal(), 0) << "device allocations not freed by vkasDestroyDevice";
        EXPECT_EQ(opRecorder.liveTotal(), 0) << "object or operation allocations not freed";
        EXPECT_TRUE(deviceRecorder.clean()) << "bad alignment, free or scope through the device's callbacks";
        EXPECT_TRUE(opRecorder.clean()) << "bad alignment, free or scope through an object's callbacks";
        EXPECT_EQ(deviceRecorder.reallocations.load(), 0);
    }

    // What a sweep expects of the command.
    struct Expect {
        uint32_t deviceScopes = kCommand;  // the scopes allowed through the device's callbacks
        uint32_t opScopes = 0;             // and through opRecorder's
        bool someAllocation = true;        // the command must allocate something (through either)
    };

    // The sweep. `call` runs the command and returns its VkResult; `onSuccess` checks and undoes a successful run;
    // `onFailure` checks that a failed run left nothing half-written. A first run counts the allocations through
    // both recorders (n) and through operator new (must be 0); then allocation k fails for k in [0, n), stepped.
    template <class Call, class Success, class Failure>
    uint64_t sweep(const std::string& what, const Expect& expect, const Call& call, const Success& onSuccess,
                   const Failure& onFailure) {
        SCOPED_TRACE(what);
        const Recorder::Snapshot dev0 = deviceRecorder.snapshot(), op0 = opRecorder.snapshot();
        alloc::armFailure(kNever);
        VkResult r = call();
        const uint64_t operatorNews = alloc::allocationsSinceArm();
        alloc::disarm();
        EXPECT_EQ(r, VK_SUCCESS) << "without failure";
        if (r != VK_SUCCESS) return 0;
        EXPECT_EQ(operatorNews, 0u) << "allocations through operator new, not the callbacks";
        const uint32_t devScopes = deviceRecorder.scopesSince(dev0), opScopes = opRecorder.scopesSince(op0);
        EXPECT_EQ(devScopes & ~expect.deviceScopes, 0u) << "unexpected scopes through the device's callbacks: " << devScopes;
        EXPECT_EQ(opScopes & ~expect.opScopes, 0u) << "unexpected scopes through the object's callbacks: " << opScopes;
        EXPECT_TRUE(deviceRecorder.sameLive(dev0)) << "device allocations outlive the command";
        EXPECT_TRUE(opRecorder.sameLive(op0)) << "object allocations outlive the command";
        const uint64_t devN = uint64_t(deviceRecorder.calls - dev0.calls), opN = uint64_t(opRecorder.calls - op0.calls);
        if (expect.someAllocation) EXPECT_GT(devN + opN, 0u) << "nothing allocated: is the test exercising the path?";
        onSuccess();
        uint32_t failing = 0;
        // Both recorders' allocations, one after the other: k < devN fails the device's k-th, else the object's.
        const uint64_t n = devN + opN;
        const uint64_t step = std::max<uint64_t>(1, (n + kMaxFailingRuns - 1) / kMaxFailingRuns);
        for (uint64_t k = 0; k < n; k += step) {
            Recorder& rec = k < devN ? deviceRecorder : opRecorder;
            const Recorder::Snapshot d = deviceRecorder.snapshot(), o = opRecorder.snapshot();
            const int64_t newBytes = alloc::liveBytes();
            rec.injected = false;
            rec.failAt = rec.calls.load() + int64_t(k < devN ? k : k - devN);
            r = call();
            rec.failAt = -1;
            if (!rec.injected) {  // fewer allocations this time (several threads): it must have worked
                EXPECT_EQ(r, VK_SUCCESS) << "allocation " << k << " of " << n << " did not fail";
                if (r == VK_SUCCESS) onSuccess();
                continue;
            }
            ++failing;
            EXPECT_EQ(r, VK_ERROR_OUT_OF_HOST_MEMORY) << "allocation " << k << " of " << n << " failing";
            EXPECT_TRUE(deviceRecorder.sameLive(d)) << "allocation " << k << " failing: device allocations leaked";
            EXPECT_TRUE(opRecorder.sameLive(o)) << "allocation " << k << " failing: object allocations leaked";
            EXPECT_EQ(alloc::liveBytes(), newBytes) << "allocation " << k << " failing: operator new bytes leaked";
            if (r == VK_SUCCESS) {
                onSuccess();
            } else {
                onFailure();
            }
            if (::testing::Test::HasFailure()) return n;
        }
        r = call();
        EXPECT_EQ(r, VK_SUCCESS) << "after the failing runs";
        if (r == VK_SUCCESS) onSuccess();
        std::cout << "[  SWEEP   ] " << what << ": " << devN << " allocations through the device's callbacks, " << opN
                  << " through the operation's, " << failing << " failing runs" << std::endl;
        return n;
    }

    // Creates an operation (with opCallbacks, or none: the device's), runs `command` on it, joins it with the crew,
    // destroys it; returns the result.
    template <class Command>
    VkResult deferred(JoinCrew& crew, bool ownCallbacks, const Command& command) {
        VkDeferredOperationKHR op = VK_NULL_HANDLE;
        const VkAllocationCallbacks* cb = ownCallbacks ? &opCallbacks : nullptr;
        VkResult r = vkCreateDeferredOperationKHR(device, cb, &op);
        if (r != VK_SUCCESS) return r;
        r = command(op);
        if (r == VK_OPERATION_DEFERRED_KHR) {
            const bool ok = crew.joinAll(op);
            r = vkGetDeferredOperationResultKHR(device, op);
            if (!ok) r = VK_ERROR_UNKNOWN;
        } else if (vkGetDeferredOperationResultKHR(device, op) != VK_SUCCESS) {
            r = VK_ERROR_UNKNOWN;
        }
        vkDestroyDeferredOperationKHR(device, op, cb);
        return r;
    }

    // A build (BUILD) of `pb`, then its UPDATE into a second structure: not deferred, deferred on an operation with
    // its own callbacks joined by 1 thread, and on one without (the device's) joined by 3.
    void sweepBuild(const std::string& what, PreparedBuild& pb, bool update) {
        SCOPED_TRACE(what);
        const VkAccelerationStructureBuildRangeInfoKHR* ranges = pb.ranges.data();
        ASSERT_EQ(vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 1, &pb.info, &ranges), VK_SUCCESS);
        const std::vector<uint8_t> reference = structureBytes(pb.as);
        std::vector<uint8_t> before(pb.as->size);
        auto run = [&](VkDeferredOperationKHR op) {
            keepBlock(before, pb.as);
            return vk.vkBuildAccelerationStructuresKHR(device, op, 1, &pb.info, &ranges);
        };
        auto same = [&] { EXPECT_TRUE(structureBytes(pb.as) == reference) << "bytes differ from the reference"; };
        auto untouchedOrUnconstructed = [&] {
            EXPECT_TRUE(wholeBlock(pb.as) == before || magicOf(pb.as) != vkas::format::kMagic)
                << "a failed build left a structure that looks whole";
        };
        JoinCrew one(0, vkDeferredOperationJoinKHR, device), three(2, vkDeferredOperationJoinKHR, device);
        sweep("build", Expect{}, [&] { return run(VK_NULL_HANDLE); }, same, untouchedOrUnconstructed);
        sweep("deferred build, own callbacks, 1 thread", Expect{kCommand | kDevice, kCommand | kObject},
              [&] { return deferred(one, true, run); }, same, untouchedOrUnconstructed);
        sweep("deferred build, device's callbacks, 3 threads", Expect{kCommand | kObject | kDevice, 0},
              [&] { return deferred(three, false, run); }, same, untouchedOrUnconstructed);
        if (!update) return;
        ASSERT_TRUE(pb.info.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR);
        AccelStruct* dst = createAccelStruct(pb.as->type, pb.as->size, {});
        VkAccelerationStructureBuildGeometryInfoKHR up = pb.info;
        up.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        up.srcAccelerationStructure = pb.as->handle;
        up.dstAccelerationStructure = dst->handle;
        up.scratchData.hostAddress = nullptr;
        std::vector<uint8_t> updateReference, dstBefore(dst->size);
        auto runUpdate = [&](VkDeferredOperationKHR op) {
            keepBlock(dstBefore, dst);
            return vk.vkBuildAccelerationStructuresKHR(device, op, 1, &up, &ranges);
        };
        auto updated = [&] {
            if (updateReference.empty())
                updateReference = structureBytes(dst);
            else
                EXPECT_TRUE(structureBytes(dst) == updateReference) << "bytes differ from the first update's";
        };
        auto unchanged = [&] { EXPECT_TRUE(wholeBlock(dst) == dstBefore) << "a failed update wrote its destination"; };
        sweep("update", Expect{}, [&] { return runUpdate(VK_NULL_HANDLE); }, updated, unchanged);
        sweep("deferred update, own callbacks, 1 thread", Expect{kCommand | kDevice, kCommand | kObject},
              [&] { return deferred(one, true, runUpdate); }, updated, unchanged);
        sweep("deferred update, device's callbacks, 3 threads", Expect{kCommand | kObject | kDevice, 0},
              [&] { return deferred(three, false, runUpdate); }, updated, unchanged);
    }

    Recorder deviceRecorder, opRecorder;
    VkAllocationCallbacks deviceCallbacks_{}, opCallbacks{};
    PFN_vkCreateDeferredOperationKHR vkCreateDeferredOperationKHR = nullptr;
    PFN_vkDestroyDeferredOperationKHR vkDestroyDeferredOperationKHR = nullptr;
    PFN_vkGetDeferredOperationResultKHR vkGetDeferredOperationResultKHR = nullptr;
    PFN_vkDeferredOperationJoinKHR vkDeferredOperationJoinKHR = nullptr;
    PFN_vkCreateMicromapEXT vkCreateMicromapEXT = nullptr;
    PFN_vkDestroyMicromapEXT vkDestroyMicromapEXT = nullptr;
    PFN_vkGetMicromapBuildSizesEXT vkGetMicromapBuildSizesEXT = nullptr;
    PFN_vkBuildMicromapsEXT vkBuildMicromapsEXT = nullptr;
};

// ---- The device and objects -------------------------------------------------------------------------------------

TEST_F(allocation_callbacks, device_creation) {
    Recorder rec;
    const VkAllocationCallbacks cb = rec.callbacks();
    VkasDeviceCreateInfo ci{};
    ci.workerThreadCount = 2;
    for (int64_t failAt = 0;; ++failAt) {
        ASSERT_LT(failAt, 16) << "never succeeded";
        rec.failAt = failAt;
        rec.calls = 0;
        rec.injected = false;
        VkDevice other = reinterpret_cast<VkDevice>(uintptr_t(0x5EED));
        alloc::armFailure(kNever);
        const VkResult r = vkasCreateDeviceWithAllocator(&ci, &cb, &other);
        const uint64_t operatorNews = alloc::allocationsSinceArm();
        alloc::disarm();
        if (rec.injected) {
            EXPECT_EQ(r, VK_ERROR_OUT_OF_HOST_MEMORY);
            EXPECT_EQ(other, reinterpret_cast<VkDevice>(uintptr_t(0x5EED))) << "a failed creation wrote pDevice";
            EXPECT_EQ(rec.liveTotal(), 0);
            continue;
        }
        ASSERT_EQ(r, VK_SUCCESS);
        EXPECT_EQ(operatorNews, 0u);
        EXPECT_GT(rec.made[VK_SYSTEM_ALLOCATION_SCOPE_DEVICE].load(), 0) << "the device is not in the callbacks' memory";
        EXPECT_EQ(rec.made[VK_SYSTEM_ALLOCATION_SCOPE_COMMAND].load() + rec.made[VK_SYSTEM_ALLOCATION_SCOPE_OBJECT].load(),
                  0);
        // vkDestroyDevice checks that the callbacks match (00379), then frees through them.
        auto destroy = reinterpret_cast<PFN_vkDestroyDevice>(vkasGetDeviceProcAddr(other, "vkDestroyDevice"));
        ASSERT_NE(destroy, nullptr);
        destroy(other, &cb);
        EXPECT_EQ(rec.liveTotal(), 0) << "vkDestroyDevice left device allocations";
        break;
    }
    EXPECT_TRUE(rec.clean());
    // vkDestroyDevice without the callbacks the device was created with is 00379; nothing is destroyed.
    VkDevice other = VK_NULL_HANDLE;
    rec.failAt = -1;
    ASSERT_EQ(vkasCreateDeviceWithAllocator(&ci, &cb, &other), VK_SUCCESS);
    auto destroy = reinterpret_cast<PFN_vkDestroyDevice>(vkasGetDeviceProcAddr(other, "vkDestroyDevice"));
    testing::internal::CaptureStderr();
    destroy(other, nullptr);
    const std::string out = testing::internal::GetCapturedStderr();
    EXPECT_NE(out.find("VUID-vkDestroyDevice-device-00379"), std::string::npos) << out;
    EXPECT_GT(rec.liveTotal(), 0) << "an invalid vkDestroyDevice destroyed the device";
    vkasDestroyDevice(other);
    EXPECT_EQ(rec.liveTotal(), 0);
}

TEST_F(allocation_callbacks, object_creation) {
    HostBuffer* hb = createBuffer(4096);
    VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bci.size = 4096;
    bci.usage = kAsBufferUsage;
    VkAccelerationStructureCreateInfoKHR aci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    aci.buffer = hb->buffer;
    aci.size = 4096;
    aci.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    uint64_t handle = 0;
    const uint64_t kUntouched = 0x5EED;
    const VkAllocationCallbacks* cb = &opCallbacks;
    auto check = [&](const char* name, auto create, auto destroy) {
        SCOPED_TRACE(name);
        for (int64_t failAt = 0;; ++failAt) {
            ASSERT_LT(failAt, 16) << "never succeeded";
            const Recorder::Snapshot d = deviceRecorder.snapshot(), o = opRecorder.snapshot();
            opRecorder.injected = false;
            opRecorder.failAt = opRecorder.calls + failAt;
            handle = kUntouched;
            alloc::armFailure(kNever);
            const VkResult r = create();
            const uint64_t operatorNews = alloc::allocationsSinceArm();
            alloc::disarm();
            opRecorder.failAt = -1;
            if (opRecorder.injected) {
                EXPECT_EQ(r, VK_ERROR_OUT_OF_HOST_MEMORY);
                EXPECT_EQ(handle, kUntouched);
                EXPECT_TRUE(opRecorder.sameLive(o) && deviceRecorder.sameLive(d)) << "leaked";
                continue;
            }
            ASSERT_EQ(r, VK_SUCCESS);
            EXPECT_EQ(operatorNews, 0u) << "allocations through operator new";
            EXPECT_EQ(opRecorder.scopesSince(o), kObject) << "the object is not in its pAllocator's memory, scope OBJECT";
            EXPECT_EQ(deviceRecorder.scopesSince(d) & ~kDevice, 0u) << "the live set: the device's, scope DEVICE";
            destroy();
            EXPECT_TRUE(opRecorder.sameLive(o)) << "destroying did not free through pfnFree";
            break;
        }
    };
    check("buffer", [&] { return vk.vkCreateBuffer(device, &bci, cb, reinterpret_cast<VkBuffer*>(&handle)); },
          [&] { vk.vkDestroyBuffer(device, reinterpret_cast<VkBuffer>(handle), cb); });
    VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    mai.allocationSize = 8192;
    check("memory", [&] { return vk.vkAllocateMemory(device, &mai, cb, reinterpret_cast<VkDeviceMemory*>(&handle)); },
          [&] { vk.vkFreeMemory(device, reinterpret_cast<VkDeviceMemory>(handle), cb); });
    check("acceleration structure",
          [&] {
              return vk.vkCreateAccelerationStructureKHR(device, &aci, cb,
                                                         reinterpret_cast<VkAccelerationStructureKHR*>(&handle));
          },
          [&] { vk.vkDestroyAccelerationStructureKHR(device, reinterpret_cast<VkAccelerationStructureKHR>(handle), cb); });
    check("deferred operation",
          [&] { return vkCreateDeferredOperationKHR(device, cb, reinterpret_cast<VkDeferredOperationKHR*>(&handle)); },
          [&] { vkDestroyDeferredOperationKHR(device, reinterpret_cast<VkDeferredOperationKHR>(handle), cb); });
}

// ---- Builds -----------------------------------------------------------------------------------------------------

TEST_F(allocation_callbacks, build_triangles) {
    auto geometry = makeGeometry(triangleSoup(6000, rng, 0.1f), VK_INDEX_TYPE_UINT32);
    for (auto [name, flags] : {std::pair{"default", 0u},
                               std::pair{"PREFER_FAST_BUILD", uint32_t(VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR)},
                               std::pair{"PREFER_FAST_TRACE", uint32_t(VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR)}}) {
        auto pb = prepareBlas({geometry.get()},
                              BuildOptions{flags | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR});
        sweepBuild(std::string("triangles, ") + name, *pb, true);
    }
}

TEST_F(allocation_callbacks, build_aabbs) {
    std::vector<VkAabbPositionsKHR> boxes;
    for (uint32_t i = 0; i < 3000; ++i) {
        const float x = rng.uniformf(-4, 4), y = rng.uniformf(-4, 4), z = rng.uniformf(-4, 4);
        boxes.push_back({x - 0.1f, y - 0.1f, z - 0.1f, x + 0.1f, y + 0.1f, z + 0.1f});
    }
    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    g.geometryType = VK_GEOMETRY_TYPE_AABBS_KHR;
    g.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
    g.geometry.aabbs.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
    g.geometry.aabbs.data.hostAddress = boxes.data();
    g.geometry.aabbs.stride = sizeof(VkAabbPositionsKHR);
    VkAccelerationStructureBuildRangeInfoKHR range{};
    range.primitiveCount = uint32_t(boxes.size());
    for (auto [name, flags] : {std::pair{"default", 0u},
                               std::pair{"PREFER_FAST_BUILD", uint32_t(VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR)},
                               std::pair{"PREFER_FAST_TRACE", uint32_t(VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR)}}) {
        auto pb = prepareBlas({g}, {range}, BuildOptions{flags | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR});
        sweepBuild(std::string("aabbs, ") + name, *pb, true);
    }
}

TEST_F(allocation_callbacks, build_instances) {
    auto geometry = makeGeometry(icosphere(1), VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    AccelStruct* blas = buildBlas(*geometry);
    std::vector<Instance> instances(5000);
    for (auto& inst : instances) {
        inst.transform = randomTransform(rng, 0.05f, 0.2f, rng.coin(0.2), 20.0f);
        inst.blas = blas;
    }
    for (auto [name, flags] : {std::pair{"default", 0u},
                               std::pair{"PREFER_FAST_BUILD", uint32_t(VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR)},
                               std::pair{"PREFER_FAST_TRACE", uint32_t(VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR)}}) {
        auto pb = prepareTlas(instances, BuildOptions{flags | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR});
        sweepBuild(std::string("instances, ") + name, *pb, true);
    }
}

TEST_F(allocation_callbacks, build_sizes_and_properties) {
    auto geometry = makeGeometry(triangleSoup(300, rng, 0.2f), VK_INDEX_TYPE_UINT32);
    AccelStruct* blas = buildBlas(*geometry, BuildOptions{VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR});
    auto pb = prepareBlas({geometry.get()});
    const uint32_t count = pb->ranges[0].primitiveCount;
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    Expect none{kCommand, 0, false};
    sweep("vkGetAccelerationStructureBuildSizesKHR", none, [&] {
        vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &pb->info,
                                                   &count, &sizes);
        return VK_SUCCESS;
    }, [] {}, [] {});
    uint64_t value = 0;
    sweep("vkWriteAccelerationStructuresPropertiesKHR", none, [&] {
        return vk.vkWriteAccelerationStructuresPropertiesKHR(device, 1, &blas->handle,
                                                             VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                                                             8, &value, 8);
    }, [] {}, [] {});
}

// ---- Copies and serialization -----------------------------------------------------------------------------------

TEST_F(allocation_callbacks, copies_and_serialization) {
    auto geometry = makeGeometry(triangleSoup(500, rng, 0.2f), VK_INDEX_TYPE_UINT32);
    AccelStruct* blas = buildBlas(*geometry, BuildOptions{VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR});
    AccelStruct* blas2 = buildBlas(*geometry);
    std::vector<Instance> instances(64);
    for (size_t i = 0; i < instances.size(); ++i) {
        instances[i].transform = randomTransform(rng, 0.5f, 1.0f, false, 10.0f);
        instances[i].blas = i % 3 ? blas : blas2;
    }
    AccelStruct* tlas = buildTlas(instances);
    JoinCrew three(2, vkDeferredOperationJoinKHR, device);
    const Expect direct{kCommand, 0, false}, own{kCommand | kDevice, kCommand | kObject, true};

    const std::vector<uint8_t> blasBytes = structureBytes(blas);
    AccelStruct* copy = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, blas->size, {});
    std::vector<uint8_t> before(std::max(copy->size, tlas->size));
    auto untouchedOrUnconstructed = [&](AccelStruct* as) {
        return [&, as] {
            EXPECT_TRUE(wholeBlock(as) == before || magicOf(as) != vkas::format::kMagic)
                << "a failed copy left a structure that looks whole";
        };
    };
    for (auto mode : {VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR, VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR}) {
        VkCopyAccelerationStructureInfoKHR info{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
        info.src = blas->handle;
        info.dst = copy->handle;
        info.mode = mode;
        auto run = [&](VkDeferredOperationKHR op) {
            keepBlock(before, copy);
            return vk.vkCopyAccelerationStructureKHR(device, op, &info);
        };
        auto same = [&] { EXPECT_TRUE(structureBytes(copy) == blasBytes); };
        const std::string name = mode == VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR ? "clone" : "compact";
        sweep(name, direct, [&] { return run(VK_NULL_HANDLE); }, same, untouchedOrUnconstructed(copy));
        sweep("deferred " + name, own, [&] { return deferred(three, true, run); }, same, untouchedOrUnconstructed(copy));
    }

    uint64_t size = 0;
    ASSERT_EQ(vk.vkWriteAccelerationStructuresPropertiesKHR(device, 1, &tlas->handle,
                                                            VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR,
                                                            8, &size, 8),
              VK_SUCCESS);
    std::vector<uint64_t> reference(size / 8 + 1), blob(size / 8 + 1);
    VkCopyAccelerationStructureToMemoryInfoKHR ser{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
    ser.src = tlas->handle;
    ser.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
    ser.dst.hostAddress = reference.data();
    ASSERT_EQ(vk.vkCopyAccelerationStructureToMemoryKHR(device, VK_NULL_HANDLE, &ser), VK_SUCCESS);
    ser.dst.hostAddress = blob.data();
    auto sameBlob = [&] {
        EXPECT_EQ(std::memcmp(blob.data(), reference.data(), size), 0);
        std::fill(blob.begin(), blob.end(), 0);
    };
    sweep("serialize", direct, [&] { return vk.vkCopyAccelerationStructureToMemoryKHR(device, VK_NULL_HANDLE, &ser); },
          sameBlob, [] {});
    sweep("deferred serialize", own, [&] {
        return deferred(three, true, [&](VkDeferredOperationKHR op) {
            return vk.vkCopyAccelerationStructureToMemoryKHR(device, op, &ser);
        });
    }, sameBlob, [] {});

    // Deserialization maps the blob's handles to the device's live bottom levels (a map in command memory).
    const std::vector<uint8_t> tlasBytes = structureBytes(tlas);
    AccelStruct* loaded = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, tlas->size, {});
    VkCopyMemoryToAccelerationStructureInfoKHR des{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
    des.src.hostAddress = reference.data();
    des.dst = loaded->handle;
    des.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    auto runDes = [&](VkDeferredOperationKHR op) {
        keepBlock(before, loaded);
        return vk.vkCopyMemoryToAccelerationStructureKHR(device, op, &des);
    };
    auto sameTlas = [&] { EXPECT_TRUE(structureBytes(loaded) == tlasBytes); };
    sweep("deserialize", Expect{kCommand, 0, true}, [&] { return runDes(VK_NULL_HANDLE); }, sameTlas,
          untouchedOrUnconstructed(loaded));
    sweep("deferred deserialize", own, [&] { return deferred(three, true, runDes); }, sameTlas,
          untouchedOrUnconstructed(loaded));
}

// ---- Micromaps --------------------------------------------------------------------------------------------------

TEST_F(allocation_callbacks, micromap_build) {
    // 64 triangles, 2-state, subdivision level 3 (64 micro-triangles: 16 bytes each).
    const uint32_t n = 64, level = 3, bytesPer = 16;
    std::vector<VkMicromapTriangleEXT> triangles(n);
    std::vector<uint8_t> data(n * bytesPer);
    for (uint32_t i = 0; i < n; ++i) {
        triangles[i].dataOffset = i * bytesPer;
        triangles[i].subdivisionLevel = uint16_t(level);
        triangles[i].format = uint16_t(VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT);
    }
    for (auto& b : data) b = uint8_t(rng.u32());
    VkMicromapUsageEXT usage{n, level, VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT};
    VkMicromapBuildInfoEXT info{VK_STRUCTURE_TYPE_MICROMAP_BUILD_INFO_EXT};
    info.type = VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT;
    info.mode = VK_BUILD_MICROMAP_MODE_BUILD_EXT;
    info.usageCountsCount = 1;
    info.pUsageCounts = &usage;
    info.data.hostAddress = data.data();
    info.triangleArray.hostAddress = triangles.data();
    info.triangleArrayStride = sizeof(VkMicromapTriangleEXT);
    VkMicromapBuildSizesInfoEXT sizes{VK_STRUCTURE_TYPE_MICROMAP_BUILD_SIZES_INFO_EXT};
    vkGetMicromapBuildSizesEXT(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &sizes);
    ASSERT_GT(sizes.micromapSize, 0u);
    HostBuffer* hb = createBuffer(sizes.micromapSize, VK_BUFFER_USAGE_MICROMAP_STORAGE_BIT_EXT);
    VkMicromapCreateInfoEXT ci{VK_STRUCTURE_TYPE_MICROMAP_CREATE_INFO_EXT};
    ci.buffer = hb->buffer;
    ci.size = sizes.micromapSize;
    ci.type = VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT;
    VkMicromapEXT micromap = VK_NULL_HANDLE;
    ASSERT_EQ(vkCreateMicromapEXT(device, &ci, &opCallbacks, &micromap), VK_SUCCESS);
    info.dstMicromap = micromap;
    ASSERT_EQ(vkBuildMicromapsEXT(device, VK_NULL_HANDLE, 1, &info), VK_SUCCESS);
    const std::vector<uint8_t> reference(hb->mapped, hb->mapped + sizes.micromapSize);
    auto same = [&] {
        EXPECT_TRUE(std::equal(reference.begin(), reference.end(), hb->mapped)) << "bytes differ from the reference";
    };
    JoinCrew three(2, vkDeferredOperationJoinKHR, device);
    // A micromap build may need no temporaries at all: what it allocates (if anything) must be routed.
    sweep("vkBuildMicromapsEXT", Expect{kCommand, 0, false},
          [&] { return vkBuildMicromapsEXT(device, VK_NULL_HANDLE, 1, &info); }, same, [] {});
    sweep("deferred vkBuildMicromapsEXT", Expect{kCommand | kDevice, kCommand | kObject, true},
          [&] { return deferred(three, true, [&](VkDeferredOperationKHR op) { return vkBuildMicromapsEXT(device, op, 1, &info); }); },
          same, [] {});
    vkDestroyMicromapEXT(device, micromap, &opCallbacks);
}

// ---- Tracing ----------------------------------------------------------------------------------------------------

TEST_F(allocation_callbacks, batch_trace_and_ray_query) {
    auto geometry = makeGeometry(triangleSoup(2000, rng, 0.2f), VK_INDEX_TYPE_UINT32);
    AccelStruct* blas = buildBlas(*geometry);
    AccelStruct* tlas = buildSingleInstanceTlas(blas);
    std::vector<VkasRay> rays(3000);
    for (auto& r : rays) {
        r = VkasRay{};
        r.origin[0] = rng.uniformf(-1, 1), r.origin[1] = rng.uniformf(-1, 1), r.origin[2] = -10;
        r.direction[2] = 1;
        r.tMax = 100;
    }
    std::vector<VkasHit> hits(rays.size()), reference(rays.size());
    ASSERT_EQ(vkasTraceRays(device, tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF, uint32_t(rays.size()),
                            rays.data(), reference.data()),
              VK_SUCCESS);
    auto same = [&] { EXPECT_EQ(std::memcmp(hits.data(), reference.data(), hits.size() * sizeof(VkasHit)), 0); };
    sweep("vkasTraceRays", Expect{}, [&] {
        return vkasTraceRays(device, tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF, uint32_t(rays.size()),
                             rays.data(), hits.data());
    }, same, [] {});
    PFN_vkasIntersectAabb intersect = [](void*, const VkasAabbCandidate*, float*) -> VkBool32 { return VK_FALSE; };
    sweep("vkasTraceRaysProcedural", Expect{}, [&] {
        return vkasTraceRaysProcedural(device, tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF,
                                       uint32_t(rays.size()), rays.data(), hits.data(), intersect, nullptr);
    }, same, [] {});
    // A ray query lives in the application's VkasRayQuery: it allocates nothing at all.
    sweep("vkasRayQueryInitialize/Proceed", Expect{kCommand, 0, false}, [&] {
        VkasRayQuery q;
        const float origin[3] = {0, 0, -10}, direction[3] = {0, 0, 1};
        vkasRayQueryInitialize(&q, tlas->handle, 0, 0xFF, origin, 0, direction, 100);
        while (vkasRayQueryProceed(&q)) vkasRayQueryConfirmIntersection(&q);
        return VK_SUCCESS;
    }, [] {}, [] {});
}

// ---- Validation messages ----------------------------------------------------------------------------------------

// A message far longer than the old fixed buffers (1 KiB of detail, 1.5 KiB in all) arrives whole, in memory from
// the device's allocator (scope COMMAND), freed when the report is done; when that allocation fails, the command
// fails with std::bad_alloc (VK_ERROR_OUT_OF_HOST_MEMORY at the API boundary) rather than truncating.
TEST_F(allocation_callbacks, long_validation_message_arrives_whole) {
    vkas::Device* dev = vkas::Device::fromHandle(device);
    ASSERT_NE(dev, nullptr);
    const std::string vuid = "VUID-vkBuildAccelerationStructuresKHR-pInfos-" + std::string(300, '7');
    const std::string detail(6000, 'x');
    {
        vkas::ScopedHostMemory memory(dev->commandMemory());
        const Recorder::Snapshot d = deviceRecorder.snapshot();
        vkas::Validator v(dev, "vkBuildAccelerationStructuresKHR");
        v.fail(vuid.c_str(), "pInfos[%u]: %s (end)", 4294967295u, detail.c_str());
        EXPECT_EQ(deviceRecorder.scopesSince(d), kCommand);
        EXPECT_GE(deviceRecorder.largest.load(), detail.size());
        EXPECT_TRUE(deviceRecorder.sameLive(d));
    }
    std::vector<std::string> errors = takeValidationErrors();
    ASSERT_EQ(errors.size(), 1u);
    const std::string expected = vuid + ": Validation Error: [ " + vuid +
                                 " ] | vkBuildAccelerationStructuresKHR(): pInfos[4294967295]: " + detail + " (end)";
    EXPECT_EQ(errors[0].size(), expected.size());
    EXPECT_TRUE(errors[0] == expected) << "the message was cut or changed";
    {
        vkas::ScopedHostMemory memory(dev->commandMemory());
        deviceRecorder.injected = false;
        deviceRecorder.failAt = deviceRecorder.calls.load();
        vkas::Validator v(dev, "vkBuildAccelerationStructuresKHR");
        EXPECT_THROW(v.fail(vuid.c_str(), "%s", detail.c_str()), std::bad_alloc);
        deviceRecorder.failAt = -1;
        EXPECT_TRUE(deviceRecorder.injected.load());
    }
    EXPECT_TRUE(takeValidationErrors().empty()) << "a message that could not be allocated was delivered cut";
}
