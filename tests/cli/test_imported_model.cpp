// The byte form in which the vkas tool's importer process hands a mesh file's scene back (tools/vkas/mesh_files/imported_model.hpp):
// what is encoded decodes to the same model; a result cut short anywhere, or with bytes changed, is refused with an
// exception or decodes to a model whose instances name meshes and materials it has, never a crash (ASan checks the reads).
#include <gtest/gtest.h>

#include <cstring>
#include <stdexcept>

#include "imported_model.hpp"
#include "vkas_test.hpp"

namespace vkas_tool {
namespace {

ImportedModel randomModel(vt::Rng& rng) {
    ImportedModel m;
    m.albedos.resize(1 + rng.below(3));
    for (Vec3& a : m.albedos) a = {rng.uniformf(0, 1), rng.uniformf(0, 1), rng.uniformf(0, 1)};
    m.meshes.resize(1 + rng.below(4));
    for (uint32_t i = 0; i < m.meshes.size(); ++i) {
        ImportedMesh& mesh = m.meshes[i];
        mesh.name = rng.coin() ? "" : "mesh-" + std::to_string(rng.u32());
        mesh.fileIndex = i + rng.below(3);
        mesh.positions.resize(3 + rng.below(20));
        for (Vec3& p : mesh.positions) p = {rng.uniformf(-5, 5), rng.uniformf(-5, 5), rng.uniformf(-5, 5)};
        mesh.indices.resize(3 * (1 + rng.below(10)));
        for (uint32_t& k : mesh.indices) k = rng.below(uint32_t(mesh.positions.size()));
    }
    m.instances.resize(rng.below(5));
    for (ImportedInstance& inst : m.instances) {
        inst.node = "node " + std::to_string(rng.below(100));
        inst.mesh = rng.below(uint32_t(m.meshes.size()));
        inst.material = rng.below(uint32_t(m.albedos.size()));
        for (auto& row : inst.transform.m)
            for (float& v : row) v = rng.uniformf(-2, 2);
    }
    return m;
}

bool same(Vec3 a, Vec3 b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void expectSame(const ImportedModel& a, const ImportedModel& b) {
    ASSERT_EQ(a.albedos.size(), b.albedos.size());
    for (size_t i = 0; i < a.albedos.size(); ++i) EXPECT_TRUE(same(a.albedos[i], b.albedos[i]));
    ASSERT_EQ(a.meshes.size(), b.meshes.size());
    for (size_t i = 0; i < a.meshes.size(); ++i) {
        EXPECT_EQ(a.meshes[i].name, b.meshes[i].name);
        EXPECT_EQ(a.meshes[i].fileIndex, b.meshes[i].fileIndex);
        ASSERT_EQ(a.meshes[i].positions.size(), b.meshes[i].positions.size());
        for (size_t v = 0; v < a.meshes[i].positions.size(); ++v) EXPECT_TRUE(same(a.meshes[i].positions[v], b.meshes[i].positions[v]));
        EXPECT_EQ(a.meshes[i].indices, b.meshes[i].indices);
    }
    ASSERT_EQ(a.instances.size(), b.instances.size());
    for (size_t i = 0; i < a.instances.size(); ++i) {
        EXPECT_EQ(a.instances[i].node, b.instances[i].node);
        EXPECT_EQ(a.instances[i].mesh, b.instances[i].mesh);
        EXPECT_EQ(a.instances[i].material, b.instances[i].material);
        EXPECT_EQ(std::memcmp(a.instances[i].transform.m, b.instances[i].transform.m, sizeof a.instances[i].transform.m), 0);
    }
}

TEST(imported_model, a_model_and_each_error_come_back_as_sent) {
    const uint64_t seed = vt::chooseSeed();
    vt::Rng rng(seed);
    for (int round = 0; round < 50; ++round) {
        ImportResult sent;
        sent.model = randomModel(rng);
        const ImportResult back = decodeImportResult(encodeImportResult(sent));
        ASSERT_EQ(back.kind, ImportResult::Kind::Model);
        expectSame(sent.model, back.model);
    }
    for (auto kind : {ImportResult::Kind::InputProblem, ImportResult::Kind::OtherError, ImportResult::Kind::OutOfMemory}) {
        ImportResult sent;
        sent.kind = kind;
        sent.message = "mesh 3: face 7 uses vertex 12, out of range";
        const ImportResult back = decodeImportResult(encodeImportResult(sent));
        EXPECT_EQ(back.kind, kind);
        EXPECT_EQ(back.message, sent.message);
    }
}

TEST(imported_model, a_result_cut_short_anywhere_is_refused) {
    const uint64_t seed = vt::chooseSeed();
    vt::Rng rng(seed);
    ImportResult sent;
    sent.model = randomModel(rng);
    const std::vector<uint8_t> whole = encodeImportResult(sent);
    for (size_t n = 0; n < whole.size(); ++n) {
        const std::vector<uint8_t> cut(whole.begin(), whole.begin() + n);
        EXPECT_THROW(decodeImportResult(cut), std::runtime_error) << "cut at " << n << " of " << whole.size();
    }
    std::vector<uint8_t> longer = whole;
    longer.push_back(0);
    EXPECT_THROW(decodeImportResult(longer), std::runtime_error);
}

TEST(imported_model, changed_bytes_are_refused_or_decode_to_a_consistent_model) {
    const uint64_t seed = vt::chooseSeed();
    vt::Rng rng(seed);
    int refused = 0, decoded = 0;
    for (int round = 0; round < 2000; ++round) {
        ImportResult sent;
        sent.model = randomModel(rng);
        std::vector<uint8_t> bytes = encodeImportResult(sent);
        for (uint32_t k = 1 + rng.below(4); k-- > 0;) bytes[rng.below(uint32_t(bytes.size()))] = uint8_t(rng.u32());
        try {
            const ImportResult back = decodeImportResult(bytes);
            ++decoded;
            if (back.kind != ImportResult::Kind::Model) continue;
            EXPECT_FALSE(back.model.albedos.empty());
            for (const ImportedInstance& inst : back.model.instances) {
                EXPECT_LT(inst.mesh, back.model.meshes.size());
                EXPECT_LT(inst.material, back.model.albedos.size());
            }
        } catch (const std::runtime_error&) {
            ++refused;
        }
    }
    std::printf("2000 damaged results: %d refused, %d decoded\n", refused, decoded);
    EXPECT_GT(refused, 0);
}

}  // namespace
}  // namespace vkas_tool
