// The valid-usage table test (docs/VALIDATION.md): every rule vkas checks has a case that breaks that rule, and
// only that rule, with one command call. The harness expects exactly that VUID (plus, for the few rules that no
// input can break alone, the rules the same input necessarily breaks too), VK_ERROR_VALIDATION_FAILED_EXT from a
// command that returns a VkResult, and no effect: the memory of every buffer, every host range the case watches and
// every output parameter are byte-identical before and after the call.
#pragma once

#include <cstring>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "vkas_test.hpp"

namespace vu {

// What the call returned: a VkResult, or nothing (void commands and those that return a value).
struct Outcome {
    bool hasResult = false;
    VkResult result = VK_SUCCESS;
};
inline Outcome R(VkResult r) { return {true, r}; }
inline Outcome V() { return {}; }

class Fixture;

// The deferred-operation commands (not in vt::Commands).
struct DeferredCommands {
    PFN_vkCreateDeferredOperationKHR create = nullptr;
    PFN_vkDestroyDeferredOperationKHR destroy = nullptr;
    PFN_vkGetDeferredOperationMaxConcurrencyKHR maxConcurrency = nullptr;
    PFN_vkGetDeferredOperationResultKHR result = nullptr;
    PFN_vkDeferredOperationJoinKHR join = nullptr;
    PFN_vkDestroyDevice destroyDevice = nullptr;
};

struct Case {
    std::string vuid;
    std::string variant;  // tells apart several cases of one VUID (empty: the only one)
    std::function<void(Fixture&, const vt::Commands&, VkDevice)> run;
    std::vector<std::string> alsoReported;  // rules the same input breaks necessarily (documented)
    bool hasEffect = false;                 // the command proceeds by definition (vkDestroyDevice)
    VkResult result = VK_ERROR_VALIDATION_FAILED_EXT;  // what a command returning a VkResult returns
};

// Every case; defined in cases_*.cpp.
void addMemoryCases(std::vector<Case>& cases);
void addObjectCases(std::vector<Case>& cases);
void addBuildCases(std::vector<Case>& cases);
void addCopyCases(std::vector<Case>& cases);
void addQueryCases(std::vector<Case>& cases);
void addMicromapCases(std::vector<Case>& cases);
const std::vector<Case>& allCases();

// A valid world the cases break one rule of: built structures, geometry, a second device for the -parent rules.
class Fixture : public vt::VkasTest {
  public:
    using vt::VkasTest::allBuffers;
    using vt::VkasTest::blasRegistry;
    using vt::VkasTest::bindBuffer;
    using vt::VkasTest::buildBlas;
    using vt::VkasTest::buildTlas;
    using vt::VkasTest::createAccelStruct;
    using vt::VkasTest::createBuffer;
    using vt::VkasTest::device;
    using vt::VkasTest::prepareBlas;
    using vt::VkasTest::prepareTlas;
    using vt::VkasTest::vk;

    void SetUp() override;
    void TearDown() override;

    // Runs the one command call of a case: snapshots the memory, runs fn, collects the VUIDs reported through the
    // messenger (and on stderr, where a command without a valid device reports), snapshots again.
    void call(const std::function<Outcome()>& fn);
    // Host memory the command must leave alone besides the buffers (scratch, instance arrays, output arrays).
    void watch(const void* data, size_t size);

    // Fixture-owned, watched host memory holding a copy of `size` bytes at `data` (zeros when data is NULL).
    uint8_t* hostCopy(const void* data, size_t size);
    template <class T>
    T* hostObject(const T& value) {
        return reinterpret_cast<T*>(hostCopy(&value, sizeof(T)));
    }

    // An unknown handle: points at memory that is no vkas object (vkas never dereferences it).
    template <class H>
    H bogus() {
        return reinterpret_cast<H>(&bogusStorage_[0]);
    }

    // The world.
    std::unique_ptr<vt::GeometryData> tri;       // 2 triangles, UINT32 indices
    std::unique_ptr<vt::GeometryData> triPlain;  // the same 2 triangles without indices
    std::vector<VkAabbPositionsKHR> boxes;       // 2 boxes
    vt::AccelStruct* blas = nullptr;        // built with ALLOW_UPDATE | ALLOW_COMPACTION
    vt::AccelStruct* plainBlas = nullptr;   // built without flags
    vt::AccelStruct* tlas = nullptr;        // one instance of blas, ALLOW_UPDATE | ALLOW_COMPACTION
    vt::AccelStruct* unbound = nullptr;     // a bottom-level structure whose buffer has no memory
    vt::AccelStruct* unbuilt = nullptr;     // a bottom-level structure big enough for blas, never built
    VkDevice other = VK_NULL_HANDLE;        // a second device (its validation reports to this fixture too)
    vt::Commands otherVk;
    DeferredCommands deferred;
    VkDeferredOperationKHR op = VK_NULL_HANDLE;  // complete, reusable

    // Build helpers: a prepared, valid build (its scratch and instance arrays are watched).
    std::unique_ptr<vt::PreparedBuild> triangleBuild(const vt::BuildOptions& opt = {});
    std::unique_ptr<vt::PreparedBuild> plainTriangleBuild(const vt::BuildOptions& opt = {});
    std::unique_ptr<vt::PreparedBuild> aabbBuild(const vt::BuildOptions& opt = {});
    std::unique_ptr<vt::PreparedBuild> instanceBuild(const vt::BuildOptions& opt = {});
    // An in-place update of blas (or tlas when top is true).
    std::unique_ptr<vt::PreparedBuild> updateBuild(bool top = false);
    // A top-level build of motion instances (VkAccelerationStructureMotionInstanceNV, 160-byte stride) into a
    // structure created with CREATE_MOTION: one instance of `target` (blas when null) of each type, then `edit`.
    std::unique_ptr<vt::PreparedBuild> motionInstanceBuild(
        const std::vector<VkAccelerationStructureMotionInstanceTypeNV>& types,
        const std::function<void(std::vector<VkAccelerationStructureMotionInstanceNV>&)>& edit = {},
        const vt::AccelStruct* target = nullptr);
    Outcome build(vt::PreparedBuild& pb, VkDeferredOperationKHR operation = VK_NULL_HANDLE);
    Outcome build(const std::vector<vt::PreparedBuild*>& builds);
    // A deferred operation with a build pending on it (joined to completion in TearDown).
    VkDeferredOperationKHR pendingOperation();
    // A buffer/memory/structure/operation of the other device.
    VkBuffer otherBuffer(bool bind);
    VkDeviceMemory otherMemory();
    VkAccelerationStructureKHR otherStructure();
    VkDeferredOperationKHR otherOperation();

    // Filled by call().
    bool called = false;
    Outcome outcome;
    std::vector<std::string> reported;  // VUIDs, in report order
    bool memoryUnchanged = true;
    std::string setupErrors;

  private:
    std::vector<uint8_t> snapshot();
    std::vector<std::pair<const void*, size_t>> watched_;
    std::vector<std::unique_ptr<vt::PreparedBuild>> keep_;
    std::vector<VkDeferredOperationKHR> pending_;
    std::unique_ptr<vt::AccelStruct> unboundStorage_;
    std::deque<const VkAccelerationStructureBuildRangeInfoKHR*> rangePointers_;
    std::deque<std::unique_ptr<uint8_t[]>> hostCopies_;
    alignas(16) uint64_t bogusStorage_[32] = {};
};

// The VUID part of a message the test messenger recorded ("VUID-...: text").
std::string vuidOf(const std::string& message);

}  // namespace vu

namespace vu {
inline void PrintTo(const Case& c, std::ostream* os) { *os << c.vuid << (c.variant.empty() ? "" : " " + c.variant); }
}  // namespace vu
