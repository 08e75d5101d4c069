#include "imported_model.hpp"

#include <cstring>
#include <stdexcept>
#include <type_traits>

namespace vkas_tool {
namespace {

// "VKIM" then the kind, the content, and "END!" last: a result cut short by a dying writer never decodes.
constexpr uint32_t kMagic = 0x4d494b56, kTrailer = 0x21444e45;

class Writer {
public:
    std::vector<uint8_t> bytes;
    template <class T>
    void put(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        putBytes(&v, sizeof v);
    }
    void putBytes(const void* p, size_t n) {
        const auto* b = static_cast<const uint8_t*>(p);
        bytes.insert(bytes.end(), b, b + n);
    }
    void putString(const std::string& s) {
        put<uint64_t>(s.size());
        putBytes(s.data(), s.size());
    }
    template <class T>
    void putArray(const std::vector<T>& a) {
        put<uint64_t>(a.size());
        putBytes(a.data(), a.size() * sizeof(T));
    }
};

class Reader {
public:
    explicit Reader(const std::vector<uint8_t>& b) : bytes(b) {}
    template <class T>
    T get() {
        T v;
        getBytes(&v, sizeof v);
        return v;
    }
    void getBytes(void* p, size_t n) {
        if (n > bytes.size() - at) throw std::runtime_error("the importer's result is cut short");
        if (n) std::memcpy(p, bytes.data() + at, n);
        at += n;
    }
    // A count of `size`-byte items, refused when more than the bytes left could hold (no allocation from a bad count).
    uint64_t count(size_t size) {
        const uint64_t n = get<uint64_t>();
        if (n > (bytes.size() - at) / (size ? size : 1)) throw std::runtime_error("the importer's result is damaged");
        return n;
    }
    std::string getString() {
        std::string s(count(1), '\0');
        getBytes(s.data(), s.size());
        return s;
    }
    template <class T>
    std::vector<T> getArray() {
        std::vector<T> a(count(sizeof(T)));
        getBytes(a.data(), a.size() * sizeof(T));
        return a;
    }
    bool atEnd() const { return at == bytes.size(); }

private:
    const std::vector<uint8_t>& bytes;
    size_t at = 0;
};

}  // namespace

std::vector<uint8_t> encodeImportResult(const ImportResult& r) {
    Writer w;
    w.put(kMagic);
    w.put(r.kind);
    if (r.kind != ImportResult::Kind::Model) {
        w.putString(r.message);
    } else {
        const ImportedModel& m = r.model;
        w.putArray(m.albedos);
        w.put<uint64_t>(m.meshes.size());
        for (const ImportedMesh& mesh : m.meshes) {
            w.putString(mesh.name);
            w.put(mesh.fileIndex);
            w.putArray(mesh.positions);
            w.putArray(mesh.indices);
        }
        w.put<uint64_t>(m.instances.size());
        for (const ImportedInstance& inst : m.instances) {
            w.putString(inst.node);
            w.put(inst.mesh);
            w.put(inst.material);
            w.put(inst.transform.m);
        }
    }
    w.put(kTrailer);
    return std::move(w.bytes);
}

ImportResult decodeImportResult(const std::vector<uint8_t>& bytes) {
    Reader r(bytes);
    if (r.get<uint32_t>() != kMagic) throw std::runtime_error("the importer's result is damaged");
    ImportResult result;
    result.kind = r.get<ImportResult::Kind>();
    switch (result.kind) {
        case ImportResult::Kind::InputProblem:
        case ImportResult::Kind::OtherError:
        case ImportResult::Kind::OutOfMemory: result.message = r.getString(); break;
        case ImportResult::Kind::Model: {
            ImportedModel& m = result.model;
            m.albedos = r.getArray<Vec3>();
            if (m.albedos.empty()) throw std::runtime_error("the importer's result has no material");
            m.meshes.resize(r.count(8 + 4 + 8 + 8));
            for (ImportedMesh& mesh : m.meshes) {
                mesh.name = r.getString();
                mesh.fileIndex = r.get<uint32_t>();
                mesh.positions = r.getArray<Vec3>();
                mesh.indices = r.getArray<uint32_t>();
            }
            m.instances.resize(r.count(8 + 4 + 4 + sizeof(Affine::m)));
            for (ImportedInstance& inst : m.instances) {
                inst.node = r.getString();
                inst.mesh = r.get<uint32_t>();
                inst.material = r.get<uint32_t>();
                r.getBytes(inst.transform.m, sizeof inst.transform.m);
                if (inst.mesh >= m.meshes.size() || inst.material >= m.albedos.size())
                    throw std::runtime_error("the importer's result places a mesh or material it does not have");
            }
            break;
        }
        default: throw std::runtime_error("the importer's result is damaged");
    }
    if (r.get<uint32_t>() != kTrailer || !r.atEnd()) throw std::runtime_error("the importer's result is damaged");
    return result;
}

}  // namespace vkas_tool
