// Hit files (--dump-hits, --compare-hits): every ray's one-thread vkasTraceRays result for each scene and ray kind
// of a run, so that two vkas builds (e.g. two structure formats) can be compared on the bench's scenes.
//
// The file, little-endian throughout:
//   header   "VKASHITS", u32 version (1), u32 record size (25), u32 n, n bytes: the writer (vkas version, options)
//   section  u32 'SECT', u32 n, n bytes: the scene's name, u32 ray kind (0 camera, 1 diffuse, 2 shadow),
//            u64 ray count, u64 hash of the rays (rayHash), then per ray 25 bytes: u8 hit (0 or 1), i32 instance id,
//            i32 geometry index, i32 primitive index, u32 t, u32 u, u32 v (float bits; a miss: -1, -1, -1, 0, 0, 0),
//            then u64 FNV-1a checksum of the section's bytes from 'SECT' to the last record
//   trailer  u32 'END.', u32 section count
// A reader checks the whole file (lengths, checksums, the trailer) before a run starts, and rejects it with a
// message otherwise.
#pragma once

#include "common.hpp"
#include "judge.hpp"

#include <fstream>
#include <string>

namespace vb {

// FNV-1a 64 over each ray's 8 floats (bit patterns, in order).
uint64_t rayHash(const std::vector<VkasRay>& rays);

class HitFileWriter {
public:
    HitFileWriter(const std::string& path, const std::string& writer);  // throws std::runtime_error
    void add(const std::string& scene, RayKind kind, const std::vector<VkasRay>& rays, const std::vector<Hit>& hits);
    void finish();  // the trailer; throws on a write error

private:
    std::ofstream f_;
    std::string path_;
    uint32_t sections_ = 0;
};

class HitFileReader {
public:
    struct Section {
        std::string scene;
        RayKind kind;
        uint64_t rays = 0, hash = 0;
        std::streamoff offset = 0;  // of the first record
        bool used = false;
    };
    explicit HitFileReader(const std::string& path);  // reads and checks the whole file; throws std::runtime_error
    const std::string& writer() const { return writer_; }
    const std::string& path() const { return path_; }
    // The first section of this scene and kind not yet taken (a scene may be run twice); null: none.
    Section* take(const std::string& scene, RayKind kind);
    std::vector<Hit> read(const Section& s);  // throws std::runtime_error
    const std::vector<Section>& sections() const { return sections_; }

private:
    std::ifstream f_;
    std::string path_, writer_;
    std::vector<Section> sections_;
};

// This run's hits against the file's for the same rays: identical (every field, bit for bit), ties (they differ,
// but another primitive at the same t within the agreement tolerance (report.hpp) that the oracle finds at that t,
// or both answers acceptable to the oracle), different (the rest: `different` lists the rays, `verdicts` the oracle's judgement, this run as
// "vkas" and the file as "Embree").
struct HitComparison {
    size_t rays = 0, identical = 0, ties = 0;
    std::vector<size_t> different;
    std::vector<Judgement> verdicts;
};
HitComparison compareHitSets(const std::vector<VkasRay>& rays, const std::vector<Hit>& now, const std::vector<Hit>& before,
                             bool anyHit, const Judge& judge, unsigned threads);
// One ray of `different`, several lines, as --show-disagreements prints them.
std::string hitDifferenceText(const char* kind, size_t index, const VkasRay& ray, const Hit& now, const Hit& before,
                              const Judgement& j, bool anyHit);

}  // namespace vb
