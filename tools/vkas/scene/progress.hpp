// Progress of long work on a terminal: "tracing  45%  1.23 M/s  3 s left", redrawn at most ten times a second on
// stderr. Silent when stderr is not a terminal or with --quiet, so logs and pipes get only the results.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace vkas_tool {

class Progress {
public:
    // Whether progress is shown at all: set once by main() from --quiet and isatty(stderr).
    static void configure(bool quiet);
    static bool enabled();
    // A one-line note for a step that has no measurable progress ("loading bunny.obj"); erased by the next line.
    static void note(const std::string& what);
    static void clear();  // erases a note

    Progress(std::string what, uint64_t total);
    ~Progress();  // erases the line
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    void update(uint64_t done);

private:
    std::string what_;
    uint64_t total_;
    std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace vkas_tool
