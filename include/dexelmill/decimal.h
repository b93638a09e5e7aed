/// @file decimal.h
/// @brief Decimal numbers as users write them (options, tool specs, memory sizes) and as messages
/// print them: one reading shared by every option, so that none takes a form another refuses.
#pragma once

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

namespace dexelmill {

/// @brief The whole of `text` as a finite decimal number, the nearest double to it: an optional
/// sign, digits with an optional decimal point (at least one digit), an optional exponent (e or E,
/// an optional sign, digits); blanks (spaces, tabs) around it are allowed. Nothing else, in any
/// locale: not the hexadecimal ("0x10"), "inf", "infinity" or "nan" that std::stod and strtod
/// also read, nor a number beyond a double's range (1e400, or 1e-400, which would read as 0).
/// @return std::nullopt for any other text.
inline std::optional<double> parseDecimal(std::string_view text) {
    const auto blank = [](char c) { return c == ' ' || c == '\t'; };
    std::size_t first = 0, end = text.size();
    while (first < end && blank(text[first])) ++first;
    while (end > first && blank(text[end - 1])) --end;
    std::size_t i = first;
    const auto digits = [&] {
        const std::size_t from = i;
        while (i < end && text[i] >= '0' && text[i] <= '9') ++i;
        return i - from;
    };
    if (i < end && (text[i] == '+' || text[i] == '-')) ++i;
    std::size_t mantissa = digits();
    if (i < end && text[i] == '.') {
        ++i;
        mantissa += digits();
    }
    if (mantissa == 0) return std::nullopt;
    if (i < end && (text[i] == 'e' || text[i] == 'E')) {
        ++i;
        if (i < end && (text[i] == '+' || text[i] == '-')) ++i;
        if (digits() == 0) return std::nullopt;
    }
    if (i != end) return std::nullopt;
    // std::from_chars reads this grammar but for a leading '+', whatever the locale.
    if (text[first] == '+') ++first;
    double v = 0.0;
    const auto [stop, error] = std::from_chars(text.data() + first, text.data() + end, v);
    if (error != std::errc() || stop != text.data() + end || !std::isfinite(v)) return std::nullopt;
    return v;
}

/// @brief `a` and `b` written with the same number of significant digits, the fewest from 6 up
/// that tell them apart (6 where they are equal): for a message that compares two values, which
/// then never reads "3 exceeds 3".
inline std::pair<std::string, std::string> decimalsApart(double a, double b) {
    char ta[32], tb[32];
    for (int digits = 6;; ++digits) {
        std::snprintf(ta, sizeof ta, "%.*g", digits, a);
        std::snprintf(tb, sizeof tb, "%.*g", digits, b);
        // 17 significant digits tell any two doubles apart.
        if (a == b || std::string_view(ta) != std::string_view(tb) || digits == 17) return {ta, tb};
    }
}

/// The most decimals a volume is printed with (mm^3): a thousandth of a cubic millimetre is a cube
/// 0.1 mm across, finer than the lattice measures a volume at its usual spacings, and the rounding
/// of a sum of volumes (1e-15 mm^3 where they cancel) prints as 0.
constexpr int kVolumeDecimals = 3;

/// The significant digits a large volume keeps before its decimals go: a block's 8e7 mm^3 prints
/// whole, not with decimals far below what its lattice measures, nor in exponent form.
constexpr int kVolumeDigits = 6;

/// @brief A volume as messages print it, with the unit and without an exponent: kVolumeDigits
/// significant digits, but no more than kVolumeDecimals decimals ("12.346 mm^3", "80707312 mm^3");
/// one that rounds to 0 prints "0.000 mm^3", whatever its sign.
inline std::string volumeText(double mm3) {
    int decimals = kVolumeDecimals;
    if (std::isfinite(mm3) && std::abs(mm3) >= 1.0)
        decimals = std::clamp(kVolumeDigits - 1 - int(std::floor(std::log10(std::abs(mm3)))), 0, kVolumeDecimals);
    char text[400];
    std::snprintf(text, sizeof text, "%.*f", decimals, mm3);
    std::string s = text;
    if (s.find_first_of("123456789") == std::string::npos && s.front() == '-') s.erase(0, 1);
    return s + " mm^3";
}

}  // namespace dexelmill
