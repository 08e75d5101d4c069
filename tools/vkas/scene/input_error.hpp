// Errors about the user's input (a file that is missing, unreadable, malformed, or holds nothing to trace): one
// message that names the file and the problem. main() prints it and exits with status 1, never with a crash.
#pragma once

#include <stdexcept>
#include <string>

namespace vkas_tool {

class InputError : public std::runtime_error {
public:
    // Control characters of `problem` (names and text a damaged file supplies) become spaces: one line.
    InputError(const std::string& file, const std::string& problem) : std::runtime_error(file + ": " + oneLine(problem)) {}

private:
    static std::string oneLine(std::string s) {
        for (char& c : s)
            if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
        return s;
    }
};

// Memory the machine has (physical), so that a request far larger fails with a message before it allocates.
uint64_t physicalMemoryBytes();
// Throws std::runtime_error("... needs about X GiB of memory ...") when `bytes` exceeds the physical memory.
void checkMemory(double bytes, const std::string& what);

}  // namespace vkas_tool
