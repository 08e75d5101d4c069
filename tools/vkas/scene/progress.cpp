#include "progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace vkas_tool {
namespace {
bool gEnabled = false;
}

void Progress::configure(bool quiet) { gEnabled = !quiet && isatty(STDERR_FILENO); }
bool Progress::enabled() { return gEnabled; }

void Progress::note(const std::string& what) {
    if (gEnabled) std::fprintf(stderr, "\r\033[K%s...", what.c_str());
}

void Progress::clear() {
    if (gEnabled) std::fprintf(stderr, "\r\033[K");
}

Progress::Progress(std::string what, uint64_t total)
    : what_(std::move(what)), total_(total), start_(std::chrono::steady_clock::now()), last_(start_) {
    update(0);
}

Progress::~Progress() {
    if (gEnabled) std::fprintf(stderr, "\r\033[K");
}

void Progress::update(uint64_t done) {
    if (!gEnabled) return;
    const auto now = std::chrono::steady_clock::now();
    if (done != 0 && done < total_ && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    const double s = std::chrono::duration<double>(now - start_).count();
    const double rate = s > 0 ? double(done) / s : 0;
    const double left = rate > 0 ? double(total_ - std::min(done, total_)) / rate : 0;
    std::fprintf(stderr, "\r\033[K%s %3.0f%%  %.2f M/s  %.0f s left", what_.c_str(),
                 total_ ? 100.0 * double(done) / double(total_) : 100.0, rate / 1e6, left);
}

}  // namespace vkas_tool
