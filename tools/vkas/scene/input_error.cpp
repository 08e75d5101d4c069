#include "input_error.hpp"

#include <unistd.h>

#include <cstdio>

namespace vkas_tool {

uint64_t physicalMemoryBytes() {
    const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
    return pages > 0 && size > 0 ? uint64_t(pages) * uint64_t(size) : 0;
}

void checkMemory(double bytes, const std::string& what) {
    const uint64_t have = physicalMemoryBytes();
    if (have == 0 || bytes <= double(have)) return;
    char b[256];
    std::snprintf(b, sizeof b, "%s needs about %.1f GiB of memory, more than the %.1f GiB this machine has",
                  what.c_str(), bytes / 1073741824.0, double(have) / 1073741824.0);
    throw std::runtime_error(b);
}

}  // namespace vkas_tool
