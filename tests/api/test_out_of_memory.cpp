// Out of memory (issue "bad input never crashes"): every command, run with its k-th allocation failing
// (support/alloc_failure.hpp, linked into this executable only), for k = 0, 1, 2, ... (stepped for the calls that
// allocate a lot) until a run gets through. Each failing run must return VK_ERROR_OUT_OF_HOST_MEMORY (void commands:
// no effect), free everything it allocated (the hook's live bytes are unchanged; LeakSanitizer checks again at exit
// under ASan) and leave nothing registered (vkasDestroyDevice reports leftovers as VUID-vkDestroyDevice-device-05137,
// a test failure). After the failing runs the same call succeeds and gives the reference result: the same bytes as
// a run without injection, the same hits. Deferred builds and copies are completed by 1 and 3 joined threads, and
// once with every allocation failing from some point on (no deadlock, no std::terminate). Also: the pAllocator of
// vkCreate*/vkAllocateMemory/vkCreateDeferredOperationKHR (CTS api.object_management.alloc_callback_fail).
#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <iostream>
#include <mutex>
#include <thread>

#include "alloc_failure.hpp"
#include "meshes.hpp"
#include "vkas_test.hpp"

using namespace vt;

namespace {

constexpr uint64_t kNever = uint64_t(1) << 62;  // armFailure(kNever): count allocations, fail none
constexpr uint32_t kMaxFailingRuns = 48;         // per sweep: k is stepped to stay under this

uint64_t usedSize(const AccelStruct* as) {
    uint64_t used;
    std::memcpy(&used, as->data() + 16, sizeof used);
    return used;
}

std::vector<uint8_t> structureBytes(const AccelStruct* as) {
    return std::vector<uint8_t>(as->data(), as->data() + usedSize(as));
}

// Threads that join a deferred operation on request. Started (and their std::thread state allocated) before any
// failure is armed; they wait on a condition variable, which allocates nothing.
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
    // Joins `op` on this thread and every helper, each until it is not VK_THREAD_IDLE_KHR; returns when all are done.
    // `successes` counts the joins that returned VK_SUCCESS; `bad` those that returned anything but SUCCESS or DONE.
    void joinAll(VkDeferredOperationKHR op, uint32_t& successes, uint32_t& bad) {
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
        successes = successes_, bad = bad_;
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

// VkAllocationCallbacks that count and can fail: the `failAt`-th allocation (from 0) returns NULL.
struct CountingCallbacks {
    int64_t failAt = -1;
    int64_t calls = 0, live = 0;
    VkAllocationCallbacks callbacks() {
        VkAllocationCallbacks c{};
        c.pUserData = this;
        c.pfnAllocation = &allocation;
        c.pfnReallocation = &reallocation;
        c.pfnFree = &release;
        return c;
    }
    static void* VKAPI_PTR allocation(void* user, size_t size, size_t alignment, VkSystemAllocationScope) {
        auto* self = static_cast<CountingCallbacks*>(user);
        if (self->calls++ == self->failAt) return nullptr;
        void* p = nullptr;
        if (posix_memalign(&p, std::max(alignment, sizeof(void*)), size) != 0) return nullptr;
        ++self->live;
        return p;
    }
    static void* VKAPI_PTR reallocation(void*, void*, size_t, size_t, VkSystemAllocationScope) { return nullptr; }
    static void VKAPI_PTR release(void* user, void* p) {
        if (!p) return;
        --static_cast<CountingCallbacks*>(user)->live;
        std::free(p);
    }
};

}  // namespace

class out_of_memory : public VkasTest {
  protected:
    void SetUp() override {
        VkasTest::SetUp();
#define LOAD(name) name = reinterpret_cast<PFN_##name>(vkasGetDeviceProcAddr(device, #name)); ASSERT_NE(name, nullptr);
        LOAD(vkCreateDeferredOperationKHR)
        LOAD(vkDestroyDeferredOperationKHR)
        LOAD(vkGetDeferredOperationResultKHR)
        LOAD(vkDeferredOperationJoinKHR)
#undef LOAD
        // Warm-up, so that what a call allocates once per device is not counted as a leak: the object registries
        // grow to their working size (hash tables keep their buckets), and the worker threads of vkasTraceRays start.
        std::vector<VkBuffer> buffers(256);
        VkBufferCreateInfo ci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        ci.size = 256;
        ci.usage = kAsBufferUsage;
        for (auto& b : buffers) ASSERT_EQ(vk.vkCreateBuffer(device, &ci, nullptr, &b), VK_SUCCESS);
        for (auto& b : buffers) vk.vkDestroyBuffer(device, b, nullptr);
        ASSERT_EQ(vkasTraceRays(device, VK_NULL_HANDLE, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF, 0, nullptr, nullptr),
                  VK_SUCCESS);
    }

    // The sweep. `call` runs the command under test and returns its VkResult (void commands: VK_SUCCESS when they
    // had their effect, VK_ERROR_OUT_OF_HOST_MEMORY when they had none). `onSuccess` checks a successful run's result
    // and undoes it (destroys what it created). First a run that only counts the allocations (n), then runs with
    // allocation k failing for k in [0, n), stepped to at most kMaxFailingRuns, then a last run without failure.
    // Returns n.
    uint64_t sweep(const std::string& what, const std::function<VkResult()>& call,
                   const std::function<void()>& onSuccess = [] {}) {
        SCOPED_TRACE(what);
        alloc::armFailure(kNever);
        VkResult r = call();
        const uint64_t n = alloc::allocationsSinceArm();
        alloc::disarm();
        EXPECT_EQ(r, VK_SUCCESS) << "without failure";
        if (r != VK_SUCCESS) return n;
        onSuccess();
        const uint32_t runsBefore = failingRuns_;
        const uint64_t step = std::max<uint64_t>(1, (n + kMaxFailingRuns - 1) / kMaxFailingRuns);
        for (uint64_t k = 0; k < n; k += step) {
            const int64_t before = alloc::liveBytes();
            alloc::armFailure(k);
            r = call();
            const bool injected = alloc::disarm();
            const int64_t after = alloc::liveBytes();
            if (!injected) {  // fewer allocations this time (several threads): it must have worked
                EXPECT_EQ(r, VK_SUCCESS) << "allocation " << k << " of " << n << " did not fail";
                if (r == VK_SUCCESS) onSuccess();
                continue;
            }
            ++failingRuns_;
            if (r != VK_ERROR_OUT_OF_HOST_MEMORY || after != before) {
                ADD_FAILURE() << "allocation " << k << " of " << n << " failing: result " << r << " (expected "
                              << VK_ERROR_OUT_OF_HOST_MEMORY << "), " << (after - before) << " bytes leaked";
                if (r == VK_SUCCESS) onSuccess();
                return n;
            }
        }
        r = call();
        EXPECT_EQ(r, VK_SUCCESS) << "after the failing runs";
        if (r == VK_SUCCESS) onSuccess();
        std::cout << "[  SWEEP   ] " << what << ": " << n << " allocations, " << (failingRuns_ - runsBefore)
                  << " failing runs" << std::endl;
        return n;
    }

    // One run with every allocation failing from the k-th on: the call must fail cleanly (or succeed, when it
    // needs fewer), and not hang.
    void stickyFailure(const std::string& what, uint64_t k, const std::function<VkResult()>& call,
                       const std::function<void()>& onSuccess = [] {}) {
        SCOPED_TRACE(what + ", every allocation failing from " + std::to_string(k));
        const int64_t before = alloc::liveBytes();
        alloc::armFailure(k, true);
        const VkResult r = call();
        const bool injected = alloc::disarm();
        if (!injected) {
            EXPECT_EQ(r, VK_SUCCESS);
            if (r == VK_SUCCESS) onSuccess();
            return;
        }
        EXPECT_EQ(r, VK_ERROR_OUT_OF_HOST_MEMORY);
        EXPECT_EQ(alloc::liveBytes(), before) << "bytes leaked";
    }

    // vkBuildAccelerationStructuresKHR of `pb`, without a deferred operation (crew == nullptr) or deferred on a new
    // operation joined by the crew's threads and this one. Returns the command's or the operation's result.
    VkResult build(PreparedBuild& pb, JoinCrew* crew) {
        const VkAccelerationStructureBuildRangeInfoKHR* ranges = pb.ranges.data();
        if (!crew) return vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 1, &pb.info, &ranges);
        return deferred(crew, [&](VkDeferredOperationKHR op) {
            return vk.vkBuildAccelerationStructuresKHR(device, op, 1, &pb.info, &ranges);
        });
    }

    // Creates an operation, runs `command` on it, joins it with the crew, destroys it; returns the result. A
    // template, not a std::function: the test itself allocates nothing while a failure is armed.
    template <class Command>
    VkResult deferred(JoinCrew* crew, const Command& command) {
        VkDeferredOperationKHR op = VK_NULL_HANDLE;
        VkResult r = vkCreateDeferredOperationKHR(device, nullptr, &op);
        if (r != VK_SUCCESS) return r;
        r = command(op);
        if (r == VK_OPERATION_DEFERRED_KHR) {
            uint32_t successes = 0, bad = 0;
            crew->joinAll(op, successes, bad);
            r = vkGetDeferredOperationResultKHR(device, op);
            if (successes == 0 || bad != 0) r = VK_ERROR_UNKNOWN;  // a join went wrong
        } else if (vkGetDeferredOperationResultKHR(device, op) != VK_SUCCESS) {
            r = VK_ERROR_UNKNOWN;  // the command failed but left the operation pending
        }
        vkDestroyDeferredOperationKHR(device, op, nullptr);
        return r;
    }

    // Sweeps the build (BUILD) of `pb` and its UPDATE into `updateDst` from `pb.as`, each without deferral and
    // deferred with 1 and 3 joined threads; every successful run must give the reference bytes.
    void sweepBuild(const std::string& what, PreparedBuild& pb, bool update = true) {
        SCOPED_TRACE(what);
        std::vector<uint8_t> reference;
        {
            alloc::ScopedFailure none(kNever);
            EXPECT_EQ(build(pb, nullptr), VK_SUCCESS);
        }
        reference = structureBytes(pb.as);
        auto sameBytes = [&] { EXPECT_TRUE(structureBytes(pb.as) == reference) << "bytes differ from the reference"; };
        JoinCrew one(0, vkDeferredOperationJoinKHR, device), three(2, vkDeferredOperationJoinKHR, device);
        sweep("build", [&] { return build(pb, nullptr); }, sameBytes);
        sweep("deferred build, 1 thread", [&] { return build(pb, &one); }, sameBytes);
        const uint64_t n = sweep("deferred build, 3 threads", [&] { return build(pb, &three); }, sameBytes);
        stickyFailure("deferred build, 3 threads", n / 2, [&] { return build(pb, &three); }, sameBytes);
        EXPECT_EQ(build(pb, &three), VK_SUCCESS);
        sameBytes();
        if (!update) return;
        // UPDATE: the source (built with ALLOW_UPDATE) refitted into a structure of its size.
        ASSERT_TRUE(pb.info.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR);
        BuildOptions opt;
        opt.createFlags = (pb.info.flags & VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV)
                              ? VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV
                              : 0;
        opt.motionMaxInstances = pb.ranges.empty() ? 0 : pb.ranges[0].primitiveCount;
        AccelStruct* dst = createAccelStruct(pb.as->type, pb.as->size, opt);
        PreparedBuild up;
        up.info = pb.info;
        up.ranges = pb.ranges;
        up.info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        up.info.srcAccelerationStructure = pb.as->handle;
        up.info.dstAccelerationStructure = dst->handle;
        up.info.scratchData.hostAddress = nullptr;
        up.as = dst;
        std::vector<uint8_t> updateReference;  // the first successful update's bytes
        auto updated = [&] {
            if (updateReference.empty())
                updateReference = structureBytes(dst);
            else
                EXPECT_TRUE(structureBytes(dst) == updateReference) << "bytes differ from the first update's";
        };
        sweep("update", [&] { return build(up, nullptr); }, updated);
        sweep("deferred update, 1 thread", [&] { return build(up, &one); }, updated);
        sweep("deferred update, 3 threads", [&] { return build(up, &three); }, updated);
    }

    PFN_vkCreateDeferredOperationKHR vkCreateDeferredOperationKHR = nullptr;
    PFN_vkDestroyDeferredOperationKHR vkDestroyDeferredOperationKHR = nullptr;
    PFN_vkGetDeferredOperationResultKHR vkGetDeferredOperationResultKHR = nullptr;
    PFN_vkDeferredOperationJoinKHR vkDeferredOperationJoinKHR = nullptr;
    uint32_t failingRuns_ = 0;
};

// ---- Object creation --------------------------------------------------------------------------------------------

TEST_F(out_of_memory, create_device) {
    VkasDeviceCreateInfo ci{};
    ci.workerThreadCount = 2;
    VkDevice other = VK_NULL_HANDLE;
    sweep("vkasCreateDevice", [&] { return vkasCreateDevice(&ci, &other); }, [&] {
        ASSERT_NE(other, VK_NULL_HANDLE);
        vkasDestroyDevice(other);
        other = VK_NULL_HANDLE;
    });
}

TEST_F(out_of_memory, create_objects) {
    // A failed vkCreate* leaves *pHandle as it was (docs/API.md).
    const VkBuffer kUntouched = reinterpret_cast<VkBuffer>(uintptr_t(0x5EED));
    VkBuffer buffer = kUntouched;
    VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bci.size = 4096;
    bci.usage = kAsBufferUsage;
    EXPECT_GT(sweep("vkCreateBuffer",
                    [&] {
                        VkResult r = vk.vkCreateBuffer(device, &bci, nullptr, &buffer);
                        if (r != VK_SUCCESS && buffer != kUntouched) r = VK_ERROR_UNKNOWN;
                        return r;
                    },
                    [&] {
                        vk.vkDestroyBuffer(device, buffer, nullptr);
                        buffer = kUntouched;
                    }),
              0u);

    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    mai.allocationSize = 8192;
    EXPECT_GT(sweep("vkAllocateMemory", [&] { return vk.vkAllocateMemory(device, &mai, nullptr, &memory); },
                    [&] { vk.vkFreeMemory(device, memory, nullptr); }),
              0u);

    HostBuffer* hb = createBuffer(4096);
    VkAccelerationStructureCreateInfoKHR aci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    aci.buffer = hb->buffer;
    aci.size = 4096;
    aci.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    VkAccelerationStructureKHR as = VK_NULL_HANDLE;
    EXPECT_GT(sweep("vkCreateAccelerationStructureKHR",
                    [&] { return vk.vkCreateAccelerationStructureKHR(device, &aci, nullptr, &as); },
                    [&] { vk.vkDestroyAccelerationStructureKHR(device, as, nullptr); }),
              0u);

    VkDeferredOperationKHR op = VK_NULL_HANDLE;
    EXPECT_GT(sweep("vkCreateDeferredOperationKHR", [&] { return vkCreateDeferredOperationKHR(device, nullptr, &op); },
                    [&] { vkDestroyDeferredOperationKHR(device, op, nullptr); }),
              0u);
    EXPECT_GT(failingRuns_, 0u);
}

// CTS api.object_management.alloc_callback_fail: the object's allocation goes through pAllocator; a NULL from
// pfnAllocation is VK_ERROR_OUT_OF_HOST_MEMORY with nothing left; destroying with the callbacks frees through pfnFree,
// and so does vkasDestroyDevice for an object the application forgot.
TEST_F(out_of_memory, allocation_callbacks) {
    CountingCallbacks counting;
    const VkAllocationCallbacks cb = counting.callbacks();
    HostBuffer* hb = createBuffer(4096);
    VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bci.size = 4096;
    bci.usage = kAsBufferUsage;
    VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    mai.allocationSize = 8192;
    VkAccelerationStructureCreateInfoKHR aci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    aci.buffer = hb->buffer;
    aci.size = 4096;
    aci.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;

    struct Kind {
        const char* name;
        std::function<VkResult(uint64_t*)> create;
        std::function<void(uint64_t)> destroy;
    };
    const Kind kinds[] = {
        {"buffer", [&](uint64_t* h) { return vk.vkCreateBuffer(device, &bci, &cb, reinterpret_cast<VkBuffer*>(h)); },
         [&](uint64_t h) { vk.vkDestroyBuffer(device, reinterpret_cast<VkBuffer>(h), &cb); }},
        {"memory",
         [&](uint64_t* h) { return vk.vkAllocateMemory(device, &mai, &cb, reinterpret_cast<VkDeviceMemory*>(h)); },
         [&](uint64_t h) { vk.vkFreeMemory(device, reinterpret_cast<VkDeviceMemory>(h), &cb); }},
        {"acceleration structure",
         [&](uint64_t* h) {
             return vk.vkCreateAccelerationStructureKHR(device, &aci, &cb,
                                                        reinterpret_cast<VkAccelerationStructureKHR*>(h));
         },
         [&](uint64_t h) {
             vk.vkDestroyAccelerationStructureKHR(device, reinterpret_cast<VkAccelerationStructureKHR>(h), &cb);
         }},
        {"deferred operation",
         [&](uint64_t* h) {
             return vkCreateDeferredOperationKHR(device, &cb, reinterpret_cast<VkDeferredOperationKHR*>(h));
         },
         [&](uint64_t h) { vkDestroyDeferredOperationKHR(device, reinterpret_cast<VkDeferredOperationKHR>(h), &cb); }},
    };
    for (const Kind& kind : kinds) {
        SCOPED_TRACE(kind.name);
        for (int64_t failAt = 0;; ++failAt) {
            ASSERT_LT(failAt, 16) << "never succeeded";
            counting.failAt = failAt;
            counting.calls = 0;
            uint64_t handle = 0x5EED;
            const VkResult r = kind.create(&handle);
            if (r == VK_SUCCESS) {
                EXPECT_GT(counting.live, 0) << "the object was not allocated through pAllocator";
                kind.destroy(handle);
                EXPECT_EQ(counting.live, 0) << "not freed through pfnFree";
                break;
            }
            EXPECT_EQ(r, VK_ERROR_OUT_OF_HOST_MEMORY);
            EXPECT_EQ(handle, 0x5EEDu) << "*pHandle changed by a failed create";
            EXPECT_EQ(counting.live, 0) << "leaked through pAllocator";
        }
    }
    // Left alive: vkasDestroyDevice frees it through pfnFree (and reports it, with the fixture's own objects).
    counting.failAt = -1;
    VkBuffer forgotten = VK_NULL_HANDLE;
    ASSERT_EQ(vk.vkCreateBuffer(device, &bci, &cb, &forgotten), VK_SUCCESS);
    EXPECT_EQ(counting.live, 1);
    vkasDestroyDevice(device);
    device = VK_NULL_HANDLE;
    EXPECT_EQ(counting.live, 0) << "vkasDestroyDevice did not free the object through pfnFree";
    const auto errors = takeValidationErrors();
    ASSERT_EQ(errors.size(), 1u);
    EXPECT_NE(errors[0].find("VUID-vkDestroyDevice-device-05137"), std::string::npos) << errors[0];
}

// ---- Queries ----------------------------------------------------------------------------------------------------

TEST_F(out_of_memory, build_sizes_and_properties) {
    auto geometry = makeGeometry(triangleSoup(300, rng, 0.2f), VK_INDEX_TYPE_UINT32);
    auto pb = prepareBlas({geometry.get()}, BuildOptions{VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR});
    const uint32_t maxCount = 300;
    VkAccelerationStructureBuildSizesInfoKHR expected{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &pb->info,
                                               &maxCount, &expected);
    sweep("vkGetAccelerationStructureBuildSizesKHR", [&] {
        VkAccelerationStructureBuildSizesInfoKHR s{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
        s.accelerationStructureSize = s.buildScratchSize = s.updateScratchSize = 0x5EED;
        vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &pb->info,
                                                   &maxCount, &s);
        if (s.accelerationStructureSize == 0x5EED && s.buildScratchSize == 0x5EED && s.updateScratchSize == 0x5EED)
            return VK_ERROR_OUT_OF_HOST_MEMORY;  // no effect
        return s.accelerationStructureSize == expected.accelerationStructureSize &&
                       s.buildScratchSize == expected.buildScratchSize &&
                       s.updateScratchSize == expected.updateScratchSize
                   ? VK_SUCCESS
                   : VK_ERROR_UNKNOWN;
    });
    submit({pb.get()});
    for (VkQueryType type : {VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                             VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR,
                             VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR}) {
        uint64_t reference = 0;
        ASSERT_EQ(vk.vkWriteAccelerationStructuresPropertiesKHR(device, 1, &pb->as->handle, type, 8, &reference, 8),
                  VK_SUCCESS);
        uint64_t value = 0;
        sweep("vkWriteAccelerationStructuresPropertiesKHR " + std::to_string(type),
              [&] { return vk.vkWriteAccelerationStructuresPropertiesKHR(device, 1, &pb->as->handle, type, 8, &value, 8); },
              [&] { EXPECT_EQ(value, reference); });
    }
}

// ---- Builds -----------------------------------------------------------------------------------------------------

namespace {
constexpr VkBuildAccelerationStructureFlagsKHR kUpdatable = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;

// AABBs, spheres, linear swept spheres and motion triangles over plain arrays (the structures point into them).
struct ProceduralInput {
    std::vector<VkAabbPositionsKHR> boxes;
    std::vector<Float3> positions, later;
    std::vector<float> radii;
    VkAccelerationStructureGeometrySpheresDataNV spheres{};
    VkAccelerationStructureGeometryLinearSweptSpheresDataNV lss{};
    VkAccelerationStructureGeometryMotionTrianglesDataNV motion{};
    VkAccelerationStructureGeometryKHR geometry{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    VkAccelerationStructureBuildRangeInfoKHR range{};
};

std::unique_ptr<ProceduralInput> makeInput(VkGeometryTypeKHR type, bool motionTriangles, uint32_t count, Rng& rng) {
    auto in = std::make_unique<ProceduralInput>();
    auto& g = in->geometry;
    g.geometryType = type;
    g.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
    in->range.primitiveCount = count;
    auto point = [&] { return Float3{rng.uniformf(-4, 4), rng.uniformf(-4, 4), rng.uniformf(-4, 4)}; };
    if (type == VK_GEOMETRY_TYPE_AABBS_KHR) {
        for (uint32_t i = 0; i < count; ++i) {
            const Float3 c = point();
            in->boxes.push_back({c[0] - 0.1f, c[1] - 0.1f, c[2] - 0.1f, c[0] + 0.1f, c[1] + 0.1f, c[2] + 0.1f});
        }
        g.geometry.aabbs.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
        g.geometry.aabbs.data.hostAddress = in->boxes.data();
        g.geometry.aabbs.stride = sizeof(VkAabbPositionsKHR);
    } else if (type == VK_GEOMETRY_TYPE_SPHERES_NV || type == VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV) {
        const uint32_t points = type == VK_GEOMETRY_TYPE_SPHERES_NV ? count : 2 * count;
        for (uint32_t i = 0; i < points; ++i) in->positions.push_back(point()), in->radii.push_back(rng.uniformf(0.05f, 0.2f));
        if (type == VK_GEOMETRY_TYPE_SPHERES_NV) {
            auto& s = in->spheres;
            s.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV;
            s.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
            s.vertexData.hostAddress = in->positions.data();
            s.vertexStride = sizeof(Float3);
            s.radiusFormat = VK_FORMAT_R32_SFLOAT;
            s.radiusData.hostAddress = in->radii.data();
            s.radiusStride = 4;
            s.indexType = VK_INDEX_TYPE_NONE_KHR;
            g.pNext = &s;
        } else {
            auto& l = in->lss;
            l.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_LINEAR_SWEPT_SPHERES_DATA_NV;
            l.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
            l.vertexData.hostAddress = in->positions.data();
            l.vertexStride = sizeof(Float3);
            l.radiusFormat = VK_FORMAT_R32_SFLOAT;
            l.radiusData.hostAddress = in->radii.data();
            l.radiusStride = 4;
            l.indexType = VK_INDEX_TYPE_NONE_KHR;
            l.indexingMode = VK_RAY_TRACING_LSS_INDEXING_MODE_LIST_NV;
            l.endCapsMode = VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_CHAINED_NV;
            g.pNext = &l;
        }
    } else if (motionTriangles) {
        for (uint32_t i = 0; i < 3 * count; ++i) {
            in->positions.push_back(point());
            const Float3 p = in->positions.back();
            in->later.push_back({p[0] + 0.5f, p[1], p[2]});
        }
        auto& t = g.geometry.triangles;
        t.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
        t.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        t.vertexData.hostAddress = in->positions.data();
        t.vertexStride = sizeof(Float3);
        t.maxVertex = 3 * count - 1;
        t.indexType = VK_INDEX_TYPE_NONE_KHR;
        in->motion.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV;
        in->motion.vertexData.hostAddress = in->later.data();
        t.pNext = &in->motion;
    }
    return in;
}
}  // namespace

TEST_F(out_of_memory, build_triangles) {
    // 6,000 triangles: above the size where deferred builds spread subtrees over the joined threads.
    auto geometry = makeGeometry(triangleSoup(6000, rng, 0.1f), VK_INDEX_TYPE_UINT32);
    auto pb = prepareBlas({geometry.get()}, BuildOptions{kUpdatable});
    sweepBuild("triangles", *pb);
    // The structure traces correctly after all that.
    blasRegistry[pb->as->reference()] = pb->blas;
    pb->as->blas = pb->blas;
    AccelStruct* tlas = buildSingleInstanceTlas(pb->as);
    EXPECT_GT(checkRays(tlas, randomRays(*tlas->scene, 200)), 0u);
}

TEST_F(out_of_memory, build_procedural) {
    struct Case {
        const char* name;
        VkGeometryTypeKHR type;
        bool motion;
    };
    for (const Case& c : {Case{"aabbs", VK_GEOMETRY_TYPE_AABBS_KHR, false},
                          Case{"spheres", VK_GEOMETRY_TYPE_SPHERES_NV, false},
                          Case{"linear swept spheres", VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV, false},
                          Case{"motion triangles", VK_GEOMETRY_TYPE_TRIANGLES_KHR, true}}) {
        auto input = makeInput(c.type, c.motion, 400, rng);
        BuildOptions opt{kUpdatable | (c.motion ? uint32_t(VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV) : 0u)};
        if (c.motion) opt.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
        auto pb = prepareBlas({input->geometry}, {input->range}, opt);
        sweepBuild(c.name, *pb);
    }
}

TEST_F(out_of_memory, build_instances) {
    auto geometry = makeGeometry(icosphere(1), VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    AccelStruct* blas = buildBlas(*geometry);
    std::vector<Instance> instances(5000);  // the parallel path of deferred builds
    for (auto& inst : instances) {
        inst.transform = randomTransform(rng, 0.05f, 0.2f, rng.coin(0.2), 20.0f);
        inst.customIndex = rng.u32() & 0xFFFFFF;
        inst.blas = blas;
    }
    auto pb = prepareTlas(instances, BuildOptions{kUpdatable});
    sweepBuild("instances", *pb);
    pb->as->scene = pb->scene;
    EXPECT_GT(checkRays(pb->as, randomRays(*pb->scene, 200)), 0u);

    // [NV-motion] A motion top level: the same instances as VkAccelerationStructureMotionInstanceNV (static and
    // matrix motion), 160-byte stride.
    const size_t n = 300;
    BuildOptions opt{kUpdatable | VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV};
    opt.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
    opt.motionMaxInstances = n;
    auto motion = prepareTlas(std::vector<Instance>(instances.begin(), instances.begin() + n), opt);
    motion->instanceBytes.assign(160 * n, 0);
    for (size_t i = 0; i < n; ++i) {
        VkAccelerationStructureMotionInstanceNV mi;
        std::memset(&mi, 0, sizeof mi);
        mi.type = i % 2 ? VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_MATRIX_MOTION_NV
                        : VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_STATIC_NV;
        if (i % 2) {
            auto& m = mi.data.matrixMotionInstance;
            m.transformT0 = instances[i].transform;
            m.transformT1 = compose(translation(1, 0, 0), instances[i].transform);
            m.mask = 0xFF;
            m.accelerationStructureReference = blas->reference();
        } else {
            auto& s = mi.data.staticInstance;
            s.transform = instances[i].transform;
            s.mask = 0xFF;
            s.accelerationStructureReference = blas->reference();
        }
        std::memcpy(motion->instanceBytes.data() + 160 * i, &mi, sizeof mi);
    }
    motion->geometries[0].geometry.instances.data.hostAddress = motion->instanceBytes.data();
    sweepBuild("motion instances", *motion);
}

// ---- Copies and serialization -----------------------------------------------------------------------------------

TEST_F(out_of_memory, copies_and_serialization) {
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

    // Clone and compact.
    const std::vector<uint8_t> blasBytes = structureBytes(blas);
    AccelStruct* copy = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, blas->size, {});
    for (auto mode : {VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR, VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR}) {
        VkCopyAccelerationStructureInfoKHR info{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
        info.src = blas->handle;
        info.dst = copy->handle;
        info.mode = mode;
        auto same = [&] { EXPECT_TRUE(structureBytes(copy) == blasBytes); };
        const std::string name = mode == VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR ? "clone" : "compact";
        sweep(name, [&] { return vk.vkCopyAccelerationStructureKHR(device, VK_NULL_HANDLE, &info); }, same);
        sweep("deferred " + name, [&] {
            return deferred(&three, [&](VkDeferredOperationKHR op) { return vk.vkCopyAccelerationStructureKHR(device, op, &info); });
        }, same);
    }

    // Serialization of the top level (a handle per instance).
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
    sweep("serialize", [&] { return vk.vkCopyAccelerationStructureToMemoryKHR(device, VK_NULL_HANDLE, &ser); }, sameBlob);
    sweep("deferred serialize", [&] {
        return deferred(&three, [&](VkDeferredOperationKHR op) { return vk.vkCopyAccelerationStructureToMemoryKHR(device, op, &ser); });
    }, sameBlob);

    // Deserialization into a new top level: the same bytes as the original.
    const std::vector<uint8_t> tlasBytes = structureBytes(tlas);
    AccelStruct* loaded = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, tlas->size, {});
    VkCopyMemoryToAccelerationStructureInfoKHR des{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
    des.src.hostAddress = reference.data();
    des.dst = loaded->handle;
    des.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    auto sameTlas = [&] { EXPECT_TRUE(structureBytes(loaded) == tlasBytes); };
    sweep("deserialize", [&] { return vk.vkCopyMemoryToAccelerationStructureKHR(device, VK_NULL_HANDLE, &des); }, sameTlas);
    sweep("deferred deserialize", [&] {
        return deferred(&three, [&](VkDeferredOperationKHR op) { return vk.vkCopyMemoryToAccelerationStructureKHR(device, op, &des); });
    }, sameTlas);
    loaded->scene = tlas->scene;
    EXPECT_GT(checkRays(loaded, randomRays(*tlas->scene, 100)), 0u);
}

// ---- Tracing ----------------------------------------------------------------------------------------------------

TEST_F(out_of_memory, trace_and_ray_query) {
    auto geometry = makeGeometry(icosphere(2), VK_INDEX_TYPE_UINT32);
    AccelStruct* blas = buildBlas(*geometry);
    std::vector<Instance> instances(16);
    for (auto& inst : instances) {
        inst.transform = randomTransform(rng, 0.5f, 1.0f, false, 5.0f);
        inst.blas = blas;
    }
    AccelStruct* tlas = buildTlas(instances);
    const auto rays3 = randomRays(*tlas->scene, 2000);  // 8 tasks of 256 rays over the worker threads
    std::vector<VkasRay> rays(rays3.size());
    for (size_t i = 0; i < rays.size(); ++i) {
        std::memcpy(rays[i].origin, rays3[i].origin.data(), 12), rays[i].tMin = rays3[i].tMin;
        std::memcpy(rays[i].direction, rays3[i].direction.data(), 12), rays[i].tMax = rays3[i].tMax;
    }
    std::vector<VkasHit> reference(rays.size()), hits(rays.size());
    ASSERT_EQ(vkasTraceRays(device, tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF, uint32_t(rays.size()),
                            rays.data(), reference.data()),
              VK_SUCCESS);
    auto sameHits = [&] {
        EXPECT_EQ(std::memcmp(hits.data(), reference.data(), hits.size() * sizeof(VkasHit)), 0);
        std::memset(hits.data(), 0, hits.size() * sizeof(VkasHit));
    };
    sweep("vkasTraceRays", [&] {
        return vkasTraceRays(device, tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF, uint32_t(rays.size()),
                             rays.data(), hits.data());
    }, sameHits);
    sweep("vkasTraceRaysProcedural", [&] {
        return vkasTraceRaysProcedural(device, tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF,
                                       uint32_t(rays.size()), rays.data(), hits.data(), nullptr, nullptr);
    }, sameHits);
    stickyFailure("vkasTraceRays", 1, [&] {
        return vkasTraceRays(device, tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF, uint32_t(rays.size()),
                             rays.data(), hits.data());
    }, sameHits);

    // Ray queries allocate nothing: Initialize and Proceed are unaffected.
    const Hit expected = fromBatch(reference[0]);
    sweep("vkasRayQueryInitialize/Proceed", [&] {
        VkasRayQuery q;
        vkasRayQueryInitialize(&q, tlas->handle, 0, 0xFF, rays[0].origin, rays[0].tMin, rays[0].direction,
                               rays[0].tMax);
        while (vkasRayQueryProceed(&q)) vkasRayQueryConfirmIntersection(&q);
        return identical(readHit(q, VK_TRUE), expected) ? VK_SUCCESS : VK_ERROR_UNKNOWN;
    });
}
