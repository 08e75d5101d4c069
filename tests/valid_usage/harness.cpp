#include "harness.hpp"

#include <algorithm>
#include <cstring>
#include <regex>

#include "meshes.hpp"

namespace vu {

std::string vuidOf(const std::string& message) {
    const size_t colon = message.find(": ");
    return colon == std::string::npos ? message : message.substr(0, colon);
}

void Fixture::SetUp() {
    vt::VkasTest::SetUp();
    ignoreLeaksAtTeardown = true;  // what the cases create is freed with the device
    if (HasFatalFailure()) return;
#define VU_LOAD(field, name) deferred.field = reinterpret_cast<PFN_##name>(vkasGetDeviceProcAddr(device, #name))
    VU_LOAD(create, vkCreateDeferredOperationKHR);
    VU_LOAD(destroy, vkDestroyDeferredOperationKHR);
    VU_LOAD(maxConcurrency, vkGetDeferredOperationMaxConcurrencyKHR);
    VU_LOAD(result, vkGetDeferredOperationResultKHR);
    VU_LOAD(join, vkDeferredOperationJoinKHR);
    VU_LOAD(destroyDevice, vkDestroyDevice);
#undef VU_LOAD

    const vt::Mesh quad = vt::grid(1, 1);
    tri = vt::makeGeometry(quad, VK_INDEX_TYPE_UINT32);
    triPlain = vt::makeGeometry(quad, VK_INDEX_TYPE_NONE_KHR);
    boxes = {{0, 0, 0, 1, 1, 1}, {2, 0, 0, 3, 1, 1}};

    vt::BuildOptions updatable;
    updatable.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR |
                      VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
    blas = buildBlas(*tri, updatable);
    plainBlas = buildBlas(*tri);
    vt::Instance instance;
    instance.blas = blas;
    tlas = buildTlas({instance}, updatable);
    {
        vt::HostBuffer* buffer = createBuffer(8192, vt::kAsBufferUsage, /*bind=*/false);
        VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
        ci.buffer = buffer->buffer;
        ci.size = 4096;
        ci.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
        unboundStorage_ = std::make_unique<vt::AccelStruct>();
        unbound = unboundStorage_.get();
        unbound->buffer = buffer;
        unbound->size = 4096;
        EXPECT_EQ(vk.vkCreateAccelerationStructureKHR(device, &ci, nullptr, &unbound->handle), VK_SUCCESS);
    }
    unbuilt = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, blas->size, {});
    ASSERT_EQ(deferred.create(device, nullptr, &op), VK_SUCCESS);

    VkasDeviceCreateInfo ci{};
    ci.pfnMessenger = &vt::VkasTest::messenger;
    ci.pMessengerUserData = static_cast<vt::VkasTest*>(this);
    ci.workerThreadCount = 1;
    ASSERT_EQ(vkasCreateDevice(&ci, &other), VK_SUCCESS);
    otherVk.load(other);
    const auto errors = takeValidationErrors();
    ASSERT_TRUE(errors.empty()) << "the world itself broke a rule: " << errors.front();
}

void Fixture::TearDown() {
    for (VkDeferredOperationKHR pending : pending_) {
        while (deferred.join(device, pending) != VK_SUCCESS) {
        }
        deferred.destroy(device, pending, nullptr);
    }
    if (op) deferred.destroy(device, op, nullptr);
    if (other) vkasDestroyDevice(other);  // frees what the cases created there (reported as 05137: consumed)
    takeValidationErrors();
    vt::VkasTest::TearDown();
}

uint8_t* Fixture::hostCopy(const void* data, size_t size) {
    hostCopies_.push_back(std::make_unique<uint8_t[]>(std::max<size_t>(size, 1)));
    uint8_t* p = hostCopies_.back().get();
    if (data)
        std::memcpy(p, data, size);
    else
        std::memset(p, 0, size);
    watch(p, size);
    return p;
}

void Fixture::watch(const void* data, size_t size) {
    if (data && size) watched_.emplace_back(data, size);
}

std::vector<uint8_t> Fixture::snapshot() {
    std::vector<uint8_t> bytes;
    for (vt::HostBuffer* b : allBuffers())
        if (b->mapped) bytes.insert(bytes.end(), b->mapped, b->mapped + b->size);
    for (const auto& [data, size] : watched_) {
        const auto* p = static_cast<const uint8_t*>(data);
        bytes.insert(bytes.end(), p, p + size);
    }
    return bytes;
}

void Fixture::call(const std::function<Outcome()>& fn) {
    for (const auto& e : takeValidationErrors()) setupErrors += "\n  " + e;
    const std::vector<uint8_t> before = snapshot();
    ::testing::internal::CaptureStderr();
    outcome = fn();
    const std::string err = ::testing::internal::GetCapturedStderr();
    called = true;
    for (const auto& e : takeValidationErrors()) reported.push_back(vuidOf(e));
    // Without a valid device there is no messenger: the message goes to stderr ("Validation Error: [ VUID-... ]").
    static const std::regex stderrVuid(R"(Validation Error: \[ (VUID-[A-Za-z0-9_-]+) \])");
    for (auto it = std::sregex_iterator(err.begin(), err.end(), stderrVuid); it != std::sregex_iterator(); ++it)
        reported.push_back((*it)[1]);
    memoryUnchanged = snapshot() == before;
}

std::unique_ptr<vt::PreparedBuild> Fixture::triangleBuild(const vt::BuildOptions& opt) {
    auto pb = prepareBlas({tri.get()}, opt);
    watch(pb->scratch.data(), pb->scratch.size());
    return pb;
}

std::unique_ptr<vt::PreparedBuild> Fixture::plainTriangleBuild(const vt::BuildOptions& opt) {
    auto pb = prepareBlas({triPlain.get()}, opt);
    watch(pb->scratch.data(), pb->scratch.size());
    return pb;
}

std::unique_ptr<vt::PreparedBuild> Fixture::aabbBuild(const vt::BuildOptions& opt) {
    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    g.geometryType = VK_GEOMETRY_TYPE_AABBS_KHR;
    g.geometry.aabbs.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
    g.geometry.aabbs.data.hostAddress = boxes.data();
    g.geometry.aabbs.stride = sizeof(VkAabbPositionsKHR);
    VkAccelerationStructureBuildRangeInfoKHR r{};
    r.primitiveCount = uint32_t(boxes.size());
    auto pb = prepareBlas(std::vector<VkAccelerationStructureGeometryKHR>{g},
                          std::vector<VkAccelerationStructureBuildRangeInfoKHR>{r}, opt);
    watch(pb->scratch.data(), pb->scratch.size());
    return pb;
}

std::unique_ptr<vt::PreparedBuild> Fixture::instanceBuild(const vt::BuildOptions& opt) {
    vt::Instance instance;
    instance.blas = blas;
    auto pb = prepareTlas({instance}, opt);
    watch(pb->scratch.data(), pb->scratch.size());
    watch(pb->instanceBytes.data(), pb->instanceBytes.size());
    watch(pb->instancePointerBytes.data(), pb->instancePointerBytes.size());
    return pb;
}

std::unique_ptr<vt::PreparedBuild> Fixture::updateBuild(bool top) {
    vt::BuildOptions updatable;
    updatable.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR |
                      VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
    auto pb = top ? instanceBuild(updatable) : triangleBuild(updatable);
    vt::AccelStruct* target = top ? tlas : blas;
    pb->info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
    pb->info.srcAccelerationStructure = target->handle;
    pb->info.dstAccelerationStructure = target->handle;
    return pb;
}

// A top-level build of motion instances (VkAccelerationStructureMotionInstanceNV, 160-byte stride) into a structure
// created with CREATE_MOTION: one instance of blas of each `types`, edited by `edit`.
std::unique_ptr<vt::PreparedBuild> Fixture::motionInstanceBuild(
    const std::vector<VkAccelerationStructureMotionInstanceTypeNV>& types,
    const std::function<void(std::vector<VkAccelerationStructureMotionInstanceNV>&)>& edit, const vt::AccelStruct* target) {
    std::vector<VkAccelerationStructureMotionInstanceNV> instances(types.size());
    for (size_t i = 0; i < types.size(); ++i) {
        auto& m = instances[i];
        std::memset(&m, 0, sizeof m);
        m.type = types[i];
        const VkTransformMatrixKHR identity = vt::identityTransform();
        const uint64_t ref = (target ? target : blas)->reference();
        if (types[i] == VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_STATIC_NV) {
            m.data.staticInstance.transform = identity;
            m.data.staticInstance.mask = 0xFF;
            m.data.staticInstance.accelerationStructureReference = ref;
        } else if (types[i] == VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_MATRIX_MOTION_NV) {
            m.data.matrixMotionInstance.transformT0 = identity;
            m.data.matrixMotionInstance.transformT1 = identity;
            m.data.matrixMotionInstance.mask = 0xFF;
            m.data.matrixMotionInstance.accelerationStructureReference = ref;
        } else {
            for (VkSRTDataNV* srt : {&m.data.srtMotionInstance.transformT0, &m.data.srtMotionInstance.transformT1}) {
                srt->sx = srt->sy = srt->sz = 1.0f;
                srt->qw = 1.0f;
            }
            m.data.srtMotionInstance.mask = 0xFF;
            m.data.srtMotionInstance.accelerationStructureReference = ref;
        }
    }
    if (edit) edit(instances);
    uint8_t* bytes = hostCopy(nullptr, 160 * instances.size());
    for (size_t i = 0; i < instances.size(); ++i) std::memcpy(bytes + 160 * i, &instances[i], sizeof instances[i]);
    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    g.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
    g.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
    g.geometry.instances.data.hostAddress = bytes;
    auto pb = std::make_unique<vt::PreparedBuild>();
    pb->geometries = {g};
    pb->ranges = {VkAccelerationStructureBuildRangeInfoKHR{uint32_t(instances.size()), 0, 0, 0}};
    auto& info = pb->info;
    info.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR;
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
    info.flags = VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV;
    info.geometryCount = 1;
    info.pGeometries = pb->geometries.data();
    const uint32_t count = uint32_t(instances.size());
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &count,
                                                 &sizes);
    vt::BuildOptions opt;
    opt.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
    opt.motionMaxInstances = count;
    pb->as = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, sizes.accelerationStructureSize, opt);
    info.dstAccelerationStructure = pb->as->handle;
    pb->scratch.assign(sizes.buildScratchSize, 0xAA);
    info.scratchData.hostAddress = pb->scratch.data();
    watch(pb->scratch.data(), pb->scratch.size());
    return pb;
}

Outcome Fixture::build(vt::PreparedBuild& pb, VkDeferredOperationKHR operation) {
    // A deferred build reads its parameters until it completes: the pointer array lives as long as the fixture.
    rangePointers_.push_back(pb.ranges.data());
    return R(vk.vkBuildAccelerationStructuresKHR(device, operation, 1, &pb.info, &rangePointers_.back()));
}

Outcome Fixture::build(const std::vector<vt::PreparedBuild*>& builds) {
    std::vector<VkAccelerationStructureBuildGeometryInfoKHR> infos;
    std::vector<const VkAccelerationStructureBuildRangeInfoKHR*> ranges;
    for (auto* pb : builds) {
        infos.push_back(pb->info);
        ranges.push_back(pb->ranges.data());
    }
    return R(vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, uint32_t(infos.size()), infos.data(),
                                                 ranges.data()));
}

VkDeferredOperationKHR Fixture::pendingOperation() {
    VkDeferredOperationKHR pending = VK_NULL_HANDLE;
    EXPECT_EQ(deferred.create(device, nullptr, &pending), VK_SUCCESS);
    auto pb = triangleBuild();
    EXPECT_EQ(build(*pb, pending).result, VK_OPERATION_DEFERRED_KHR);
    keep_.push_back(std::move(pb));
    pending_.push_back(pending);
    return pending;
}

VkBuffer Fixture::otherBuffer(bool bind) {
    VkBufferCreateInfo ci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    ci.size = 4096;
    ci.usage = vt::kAsBufferUsage;
    VkBuffer buffer = VK_NULL_HANDLE;
    EXPECT_EQ(otherVk.vkCreateBuffer(other, &ci, nullptr, &buffer), VK_SUCCESS);
    if (bind) {
        EXPECT_EQ(otherVk.vkBindBufferMemory(other, buffer, otherMemory(), 0), VK_SUCCESS);
    }
    return buffer;
}

VkDeviceMemory Fixture::otherMemory() {
    VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
    flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
    VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, &flags, 4096, 0};
    VkDeviceMemory memory = VK_NULL_HANDLE;
    EXPECT_EQ(otherVk.vkAllocateMemory(other, &ai, nullptr, &memory), VK_SUCCESS);
    return memory;
}

VkAccelerationStructureKHR Fixture::otherStructure() {
    VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    ci.buffer = otherBuffer(true);
    ci.size = 4096;
    ci.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    VkAccelerationStructureKHR as = VK_NULL_HANDLE;
    EXPECT_EQ(otherVk.vkCreateAccelerationStructureKHR(other, &ci, nullptr, &as), VK_SUCCESS);
    return as;
}

VkDeferredOperationKHR Fixture::otherOperation() {
    auto create = reinterpret_cast<PFN_vkCreateDeferredOperationKHR>(
        vkasGetDeviceProcAddr(other, "vkCreateDeferredOperationKHR"));
    VkDeferredOperationKHR operation = VK_NULL_HANDLE;
    EXPECT_EQ(create(other, nullptr, &operation), VK_SUCCESS);
    return operation;
}

const std::vector<Case>& allCases() {
    static const std::vector<Case> cases = [] {
        std::vector<Case> c;
        addMemoryCases(c);
        addObjectCases(c);
        addBuildCases(c);
        addCopyCases(c);
        addQueryCases(c);
        addMicromapCases(c);
        return c;
    }();
    return cases;
}

// ---- The table test -------------------------------------------------------------------------------------------

class valid_usage : public Fixture, public ::testing::WithParamInterface<Case> {};

TEST_P(valid_usage, reports_exactly_its_rule_and_has_no_effect) {
    const Case& c = GetParam();
    c.run(*this, vk, device);
    ASSERT_TRUE(called) << "the case never made its command call";
    EXPECT_TRUE(setupErrors.empty()) << "the case's setup broke rules:" << setupErrors;
    std::vector<std::string> expected{c.vuid};
    expected.insert(expected.end(), c.alsoReported.begin(), c.alsoReported.end());
    std::vector<std::string> got = reported;
    std::sort(expected.begin(), expected.end());
    std::sort(got.begin(), got.end());
    std::string list;
    for (const auto& r : reported) list += "\n  " + r;
    EXPECT_EQ(got, expected) << "reported:" << (list.empty() ? std::string(" nothing") : list);
    if (outcome.hasResult) {
        EXPECT_EQ(outcome.result, c.result);
    }
    if (!c.hasEffect) {
        EXPECT_TRUE(memoryUnchanged) << "the command changed memory it must not touch";
    }
}

std::string caseName(const ::testing::TestParamInfo<Case>& info) {
    std::string name = info.param.vuid.substr(5) + (info.param.variant.empty() ? "" : "_" + info.param.variant);
    for (char& ch : name)
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
    return name;
}

INSTANTIATE_TEST_SUITE_P(vuid, valid_usage, ::testing::ValuesIn(allCases()), caseName);

}  // namespace vu
