// Tests of the APT CL reader.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <string>

#include "dexelmill/error.h"
#include "dexelmill/path/apt.h"
#include "path/testdata.h"

using namespace dexelmill;

namespace {

bool hasDiagnostic(const Program& p, const std::string& fragment) {
    for (const Diagnostic& d : p.diagnostics)
        if (d.message.find(fragment) != std::string::npos) return true;
    return false;
}

}  // namespace

TEST_CASE("apt: every APT program of the shared testdata parses", "[path][apt]") {
    if (!test::haveSharedData()) return;
    namespace fs = std::filesystem;
    int count = 0;
    for (const auto& entry : fs::recursive_directory_iterator(test::sharedData())) {
        if (entry.path().extension() != ".apt") continue;
        INFO(entry.path().string());
        Program p;
        REQUIRE_NOTHROW(p = readApt(entry.path().string()));
        CHECK(p.path.moves.size() > 50);
        CHECK_FALSE(p.tools.empty());
        for (const Move& m : p.path.moves) {
            REQUIRE(p.tools.count(m.tool) == 1);
            REQUIRE(std::abs(glm::length(m.axis) - 1.0) < 1e-9);
        }
        CHECK(hasDiagnostic(p, "FEDRAT"));
        ++count;
    }
    CHECK(count == 4);
}
