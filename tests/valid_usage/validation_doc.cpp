// docs/VALIDATION.md against the code and the table test: every VUID the sources report is in the document as
// checked (or unreachable, with its reason), every checked VUID is reported by the sources and has a case in
// allCases(), and every case's VUID is documented as checked.
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "harness.hpp"

namespace vu {
namespace {

std::string readFile(const std::filesystem::path& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

// VUID -> status (the bold word of the third column).
std::map<std::string, std::string> documentedStatuses(std::vector<std::string>& duplicates) {
    std::map<std::string, std::string> statuses;
    static const std::regex row(R"(^\| `(VUID-[A-Za-z0-9_-]+)` \|.*\| \*\*([a-z/ ]+)\*\*)");
    std::istringstream doc(readFile(std::filesystem::path(VKAS_SOURCE_DIR) / "docs" / "VALIDATION.md"));
    for (std::string line; std::getline(doc, line);) {
        std::smatch m;
        if (!std::regex_search(line, m, row)) continue;
        if (!statuses.emplace(m[1], m[2]).second) duplicates.push_back(m[1]);
    }
    return statuses;
}

// Every VUID string literal in src/.
std::set<std::string> reportedBySources() {
    std::set<std::string> vuids;
    static const std::regex literal(R"re("(VUID-[A-Za-z0-9_]+-[A-Za-z0-9_]+(?:-[A-Za-z0-9]+)?)")re");
    for (const auto& entry : std::filesystem::recursive_directory_iterator(std::filesystem::path(VKAS_SOURCE_DIR) / "src")) {
        if (!entry.is_regular_file()) continue;
        const std::string text = readFile(entry.path());
        for (auto it = std::sregex_iterator(text.begin(), text.end(), literal); it != std::sregex_iterator(); ++it)
            vuids.insert((*it)[1]);
    }
    return vuids;
}

TEST(validation_doc, agrees_with_the_sources_and_the_cases) {
    std::vector<std::string> duplicates;
    const auto documented = documentedStatuses(duplicates);
    EXPECT_TRUE(duplicates.empty()) << "documented twice: " << duplicates.front();
    ASSERT_GT(documented.size(), 300u) << "docs/VALIDATION.md has lost its tables";
    const auto sources = reportedBySources();
    ASSERT_GT(sources.size(), 300u) << "no VUIDs found under " VKAS_SOURCE_DIR "/src";
    std::set<std::string> cased;
    for (const Case& c : allCases()) cased.insert(c.vuid);

    for (const auto& vuid : sources) {
        auto it = documented.find(vuid);
        if (it == documented.end()) {
            ADD_FAILURE() << vuid << " is reported by src/ but not in docs/VALIDATION.md";
            continue;
        }
        EXPECT_TRUE(it->second == "checked" || it->second == "unreachable")
            << vuid << " is reported by src/ but documented as " << it->second;
    }
    for (const auto& [vuid, status] : documented) {
        if (status == "checked") {
            EXPECT_TRUE(sources.count(vuid)) << vuid << " is documented as checked but src/ never reports it";
            EXPECT_TRUE(cased.count(vuid)) << vuid << " is documented as checked but has no valid_usage case";
        } else if (status == "unreachable") {
            EXPECT_TRUE(sources.count(vuid)) << vuid << " is documented as unreachable but src/ has no check";
            EXPECT_FALSE(cased.count(vuid)) << vuid << " is documented as unreachable but has a case";
        } else {
            EXPECT_FALSE(sources.count(vuid)) << vuid << " is documented as " << status << " but src/ reports it";
        }
    }
    for (const auto& vuid : cased) {
        auto it = documented.find(vuid);
        EXPECT_TRUE(it != documented.end() && it->second == "checked")
            << "the case for " << vuid << " has no 'checked' row in docs/VALIDATION.md";
    }
}

}  // namespace
}  // namespace vu
