#include "model_loader.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "imported_model.hpp"
#include "input_error.hpp"
#include "mesh_header_check.hpp"
#include "model_import.hpp"
#include "structure_file.hpp"

namespace vkas_tool {
namespace {

namespace fs = std::filesystem;

// The checks assimp would report vaguely ("No suitable reader found") or not at all, done first.
uint64_t checkReadableFile(const std::string& path) {
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (ec || !fs::exists(st)) throw InputError(path, "no such file");
    if (fs::is_directory(st)) throw InputError(path, "is a directory, not a file");
    if (!fs::is_regular_file(st)) throw InputError(path, "is not a regular file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, std::string("cannot be read: ") + std::strerror(errno));
    const uint64_t size = fs::file_size(path, ec);
    if (ec) throw InputError(path, "cannot be read: " + ec.message());
    if (size == 0) throw InputError(path, "is empty");
    return size;
}

bool finite(const Affine& a) {
    for (const auto& row : a.m)
        for (float v : row)
            if (!std::isfinite(v)) return false;
    return true;
}

bool finite(Vec3 p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

std::string meshName(const ImportedMesh& m) {
    return "mesh " + std::to_string(m.fileIndex) + (m.name.empty() ? "" : " (\"" + m.name + "\")");
}

// importModel in this process, every way it can end as an ImportResult.
ImportResult importCaught(const std::string& path) {
    ImportResult r;
    try {
        r.model = importModel(path);
    } catch (const InputError& e) {
        r.kind = ImportResult::Kind::InputProblem;
        r.message = e.what();
        if (r.message.rfind(path + ": ", 0) == 0) r.message.erase(0, path.size() + 2);
    } catch (const std::bad_alloc&) {
        r.kind = ImportResult::Kind::OutOfMemory;
    } catch (const std::exception& e) {
        r.kind = ImportResult::Kind::OtherError;
        r.message = e.what();
    } catch (...) {
        r.kind = ImportResult::Kind::OtherError;
        r.message = path + ": assimp failed with an unknown exception";
    }
    return r;
}

// Built with AddressSanitizer (VKAS_SANITIZE): the importer process keeps its stderr, and its report is a failure.
#if defined(__SANITIZE_ADDRESS__)
#define VKAS_TOOL_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define VKAS_TOOL_ASAN 1
#endif
#endif
#if defined(VKAS_TOOL_ASAN)
constexpr int kSanitized = 1;
#else
constexpr int kSanitized = 0;
#endif
constexpr int kParentGone = 3;  // the child's exit status when its result could not be written
constexpr int kAssimpMemoryError = 4;  // (sanitized builds) the child's sanitizer report lies inside assimp
int outOfMemoryExitStatus = 0;         // setImporterOutOfMemoryExitStatus

#if defined(VKAS_TOOL_ASAN)
extern "C" void __asan_set_error_report_callback(void (*callback)(const char*));

// Whether an AddressSanitizer report is about assimp's own memory handling: the first two frames of its first stack
// (frame 0 is often the sanitizer's operator delete or memcpy, frame 1 its caller) name libassimp. Debian's assimp is
// not instrumented, so ASan sees only what it does through the intercepted calls (a bad or double free on a damaged
// file, found by vkas_fuzz_mesh_file); a report whose frames are vkas's own stays a failure.
bool reportInsideAssimp(const char* report) {
    const char* frame0 = std::strstr(report, "    #0 ");
    if (!frame0) return false;
    const char* frame1 = std::strstr(frame0, "    #1 ");
    const char* end = frame1 ? std::strchr(frame1, '\n') : std::strchr(frame0, '\n');
    const std::string top(frame0, end ? size_t(end - frame0) : std::strlen(frame0));
    return top.find("libassimp") != std::string::npos;
}

// In the importer child: a report inside assimp ends the child with kAssimpMemoryError (the file is damaged for
// assimp: refused as any other), before the sanitizer aborts it as a finding.
void onSanitizerReport(const char* report) {
    if (reportInsideAssimp(report)) _exit(kAssimpMemoryError);
}
void classifySanitizerReports() { __asan_set_error_report_callback(onSanitizerReport); }
#else
void classifySanitizerReports() {}
#endif

bool writeAll(int fd, const uint8_t* p, size_t n) {
    while (n > 0) {
        const ssize_t w = write(fd, p, n);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return false;
        p += w, n -= size_t(w);
    }
    return true;
}

// assimp's importers crash, loop forever or write out of bounds without dying on some damaged files (found by
// vkas_fuzz_mesh_file; the last damages the heap of whatever process runs them, to fail much later). So assimp runs
// only in a child process, which sends the scene back as plain arrays (imported_model.hpp) and exits: a child that
// dies or overruns its time refuses the file, and the damage of one file ends with its child.
ImportResult importInChild(const std::string& path, uint64_t fileSize) {
    // No child to be had (process or memory limits): the file is read in this process, as the tool once did.
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) return importCaught(path);
    std::fflush(nullptr);
    const pid_t pid = fork();
    if (pid < 0) {
        close(fds[0]), close(fds[1]);
        return importCaught(path);
    }
    if (pid == 0) {
        close(fds[0]);
        const int null = open("/dev/null", O_WRONLY);  // what glibc prints as assimp's damage kills it: not ours
        if (null >= 0) {
            dup2(null, 1);
            if (!kSanitized) dup2(null, 2);  // a sanitizer's report stays on stderr
            close(null);
        }
        for (int sig : {SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL}) signal(sig, SIG_DFL);  // a crash is a signal
        classifySanitizerReports();
        std::vector<uint8_t> bytes;
        try {
            bytes = encodeImportResult(importCaught(path));
        } catch (...) {
            ImportResult oom;
            oom.kind = ImportResult::Kind::OutOfMemory;
            bytes = encodeImportResult(oom);
        }
        _exit(writeAll(fds[1], bytes.data(), bytes.size()) ? 0 : kParentGone);
    }
    close(fds[1]);
    // The child gets 10 s, and 1 s more per MiB of file.
    const int seconds = int(10 + fileSize / 1048576);
    const auto limit = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
    std::vector<uint8_t> bytes;
    bool timedOut = false;
    for (;;) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(limit - std::chrono::steady_clock::now());
        if (left.count() <= 0) {
            timedOut = true;
            break;
        }
        pollfd p{fds[0], POLLIN, 0};
        const int ready = poll(&p, 1, int(std::min<int64_t>(left.count(), 1000)));
        if (ready < 0 && errno != EINTR) break;
        if (ready <= 0) continue;
        uint8_t chunk[65536];
        const ssize_t n = read(fds[0], chunk, sizeof chunk);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;  // end of file: the child is done (or dead)
        bytes.insert(bytes.end(), chunk, chunk + n);
    }
    close(fds[0]);
    if (timedOut) kill(pid, SIGKILL);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (timedOut)
        throw InputError(path, "damaged: assimp's importer did not finish reading it in " + std::to_string(seconds) + " s");
    if (WIFSIGNALED(status))
        throw InputError(path, "damaged: assimp's importer crashed reading it (signal " + std::to_string(WTERMSIG(status)) + ")");
    if (outOfMemoryExitStatus != 0 && WIFEXITED(status) && WEXITSTATUS(status) == outOfMemoryExitStatus)
        throw InputError(path, "out of memory while reading it (assimp's importer asked for more than the process may have)");
    // The child exits 0 or dies by a signal; another exit status is a sanitizer's report (in a sanitized build the
    // child runs vkas's own checks instrumented, and a finding there is a bug of vkas, not a damaged file).
    if (kSanitized && WIFEXITED(status) && WEXITSTATUS(status) == kAssimpMemoryError)
        throw InputError(path, "damaged: assimp's importer mishandled its memory reading it (AddressSanitizer's report "
                               "is inside assimp)");
    if (kSanitized && WIFEXITED(status) && WEXITSTATUS(status) != 0 && WEXITSTATUS(status) != kParentGone) {
        std::fprintf(stderr, "vkas: the importer process reading %s ended with a sanitizer report (exit status %d)\n",
                     path.c_str(), WEXITSTATUS(status));
        std::abort();
    }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        throw InputError(path, "damaged: assimp's importer failed reading it (exit status " +
                                   std::to_string(WEXITSTATUS(status)) + ")");
    try {
        return decodeImportResult(bytes);
    } catch (const std::runtime_error& e) {
        throw InputError(path, std::string("damaged: ") + e.what());
    }
}

// The scene the importer found, or what it said about the file.
ImportedModel importedModel(const std::string& path, uint64_t fileSize) {
    ImportResult r = importInChild(path, fileSize);
    switch (r.kind) {
        case ImportResult::Kind::Model: return std::move(r.model);
        case ImportResult::Kind::InputProblem: throw InputError(path, r.message);
        case ImportResult::Kind::OutOfMemory: throw InputError(path, "out of memory while reading it");
        default: throw std::runtime_error(r.message);
    }
}

}  // namespace

void setImporterOutOfMemoryExitStatus(int status) { outOfMemoryExitStatus = status; }

ModelInfo loadModel(const std::string& path, Scene& scene) {
    const uint64_t fileSize = checkReadableFile(path);
    if (looksSerialized(path))
        throw InputError(path, "is a serialized acceleration structure, not a mesh (`vkas inspect` reads it)");
    checkDeclaredCounts(path, fileSize);
    checkMemory(8.0 * double(fileSize), "loading " + path);  // assimp holds the file and its own copy of the meshes
    ImportedModel model = importedModel(path, fileSize);
    if (model.meshes.empty()) throw InputError(path, "holds no triangles (only points or lines)");

    // What the tool builds from: finite vertices, indices inside their mesh, whole triangles.
    for (const ImportedMesh& m : model.meshes) {
        for (size_t v = 0; v < m.positions.size(); ++v) {
            const Vec3 p = m.positions[v];
            if (!finite(p))
                throw InputError(path, meshName(m) + ": vertex " + std::to_string(v) + " is not finite (" +
                                           std::to_string(p.x) + ", " + std::to_string(p.y) + ", " + std::to_string(p.z) + ")");
        }
        if (m.indices.size() % 3 != 0) throw InputError(path, meshName(m) + ": a triangle with fewer than three corners");
        for (size_t k = 0; k < m.indices.size(); ++k)
            if (m.indices[k] >= m.positions.size())
                throw InputError(path, meshName(m) + ": triangle " + std::to_string(k / 3) + " uses vertex " +
                                           std::to_string(m.indices[k]) + ", but the mesh has " +
                                           std::to_string(m.positions.size()) + " vertices");
    }

    ModelInfo info;
    info.path = path;
    const uint32_t firstMaterial = static_cast<uint32_t>(scene.materials.size());
    for (const Vec3& albedo : model.albedos) scene.materials.push_back({albedo});

    // One bottom level per mesh (all have triangles): mesh i is bottom level firstBlas + i.
    const uint32_t firstBlas = static_cast<uint32_t>(scene.blases.size());
    for (ImportedMesh& im : model.meshes) {
        Mesh m;
        m.name = std::move(im.name);
        m.positions = std::move(im.positions);
        m.indices = std::move(im.indices);
        m.computeNormals();
        info.triangles += m.triangleCount();
        info.vertices += m.positions.size();
        scene.meshes.push_back(std::make_unique<Mesh>(std::move(m)));
        BlasDesc blas;
        blas.name = scene.meshes.back()->name.empty() ? "mesh " + std::to_string(im.fileIndex) : scene.meshes.back()->name;
        blas.geometries.push_back({scene.meshes.back().get(), VertexLayout::Float3, VK_INDEX_TYPE_UINT32, {},
                                   VK_GEOMETRY_OPAQUE_BIT_KHR});
        scene.blases.push_back(std::move(blas));
        ++info.meshes;
    }

    for (const ImportedInstance& im : model.instances) {
        if (!finite(im.transform))
            throw InputError(path, "node \"" + im.node + "\" has a non-finite transform");
        // An instance transform must be invertible (VUID-VkTransformMatrixKHR-matrix-03799: vkas refuses the
        // build otherwise); the same determinant in double precision.
        const auto& m = im.transform.m;
        const double det = double(m[0][0]) * (double(m[1][1]) * m[2][2] - double(m[1][2]) * m[2][1]) -
                           double(m[0][1]) * (double(m[1][0]) * m[2][2] - double(m[1][2]) * m[2][0]) +
                           double(m[0][2]) * (double(m[1][0]) * m[2][1] - double(m[1][1]) * m[2][0]);
        if (!(det != 0.0 && std::isfinite(det)))
            throw InputError(path, "node \"" + im.node + "\" has a transform that is not invertible");
        InstanceDesc inst;
        inst.blas = firstBlas + im.mesh;
        inst.transform = im.transform;
        inst.customIndex = firstMaterial + im.material;
        // Files disagree on winding and many meshes are open: shade both sides.
        inst.flags = VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR;
        scene.instances.push_back(inst);
        ++info.instances;
    }
    if (info.instances == 0) throw InputError(path, "no node of the file places its meshes");
    return info;
}

Box instancedBounds(const Scene& scene) {
    constexpr float inf = std::numeric_limits<float>::infinity();
    Box b{{inf, inf, inf}, {-inf, -inf, -inf}};
    for (const InstanceDesc& inst : scene.instances) {
        const BlasDesc& blas = scene.blases.at(inst.blas);
        for (const GeometryDesc& g : blas.geometries) {
            const Affine x = g.transform ? inst.transform * *g.transform : inst.transform;
            for (const Vec3& p : g.mesh->positions) {
                const Vec3 w = x.point(p);
                b.lo = {std::min(b.lo.x, w.x), std::min(b.lo.y, w.y), std::min(b.lo.z, w.z)};
                b.hi = {std::max(b.hi.x, w.x), std::max(b.hi.y, w.y), std::max(b.hi.z, w.z)};
            }
        }
    }
    return b;
}

}  // namespace vkas_tool
