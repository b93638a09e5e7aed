/// @file gcode_run.h
/// @brief Test support for the program readers' tests: a G-code text run as LinuxCNC runs it, a
/// place compared within a tolerance, and the diagnostics looked up by a fragment of their text.
#pragma once

#include <cmath>
#include <string>

#include "dexelmill/path/gcode.h"
#include "dexelmill/path/toolpath.h"

namespace dexelmill::testing {

/// Places (mm) and angles (degrees) worked out by hand: equal up to the rounding of a few
/// operations.
constexpr double kPlaceTol = 1e-9;

/// Options as LinuxCNC runs a program: the machine starts at the origin.
inline GcodeOptions linuxcnc() {
    GcodeOptions o;
    o.startPosition = Vec3(0.0);
    return o;
}

/// `text` read as the G-code file "test.ngc".
inline Program runGcode(const std::string& text, GcodeOptions options = linuxcnc()) {
    return parseGcode(text, "test.ngc", options);
}

inline bool near(const Vec3& a, const Vec3& b, double tol = kPlaceTol) {
    return std::abs(a.x - b.x) <= tol && std::abs(a.y - b.y) <= tol && std::abs(a.z - b.z) <= tol;
}

/// The first diagnostic whose message holds `fragment`; nullptr if none does.
inline const Diagnostic* findDiagnostic(const Program& p, const std::string& fragment) {
    for (const Diagnostic& d : p.diagnostics)
        if (d.message.find(fragment) != std::string::npos) return &d;
    return nullptr;
}

inline bool hasDiagnostic(const Program& p, const std::string& fragment) {
    return findDiagnostic(p, fragment) != nullptr;
}

}  // namespace dexelmill::testing
