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

namespace detail {

/// `value` in fixed notation, never with an exponent: `digits` significant digits, but no more than
/// `maxDecimals` decimals (a large value prints whole); one that rounds to 0 prints without a sign.
/// With `trim`, the zeros that end the decimals go, and the point with them ("0.125", "5").
inline std::string fixedText(double value, int digits, int maxDecimals, bool trim) {
    int decimals = maxDecimals;
    if (std::isfinite(value) && value != 0.0)
        decimals = std::clamp(digits - 1 - int(std::floor(std::log10(std::abs(value)))), 0, maxDecimals);
    char text[400];  // a double below 1e309 has at most 309 digits before the point
    std::snprintf(text, sizeof text, "%.*f", decimals, value);
    std::string s = text;
    if (s.find_first_of("123456789") == std::string::npos && s.front() == '-') s.erase(0, 1);
    if (trim && s.find('.') != std::string::npos) {
        s.erase(s.find_last_not_of('0') + 1);
        if (s.back() == '.') s.pop_back();
    }
    return s;
}

}  // namespace detail

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
inline std::string volumeText(double mm3) { return detail::fixedText(mm3, kVolumeDigits, kVolumeDecimals, false) + " mm^3"; }

/// The significant digits a length is printed with, as "%.4g" printed them: enough to tell a
/// deviation of 0.125 mm from one of 0.1251 mm.
constexpr int kLengthDigits = 4;

/// The most decimals a length is printed with (mm): a nanometre. An STL stores single-precision
/// coordinates, which round by 6e-8 of their size (0.6 nm at 10 mm), so figures below a nanometre
/// say nothing about a part; a length that rounds to 0 at that is rounding, and prints as 0.
constexpr int kLengthDecimals = 6;

/// @brief A length (mm) as messages print it, without the unit and never with an exponent:
/// kLengthDigits significant digits, at most kLengthDecimals decimals, no trailing zeros ("0.125",
/// "5", "0.05145", "12346"); one that rounds to 0 prints "0", whatever its sign.
inline std::string lengthText(double mm) { return detail::fixedText(mm, kLengthDigits, kLengthDecimals, true); }

/// @brief lengthText with a "+" before a positive length that does not round to 0 ("+0.05",
/// "-0.01", "0"), for a range's ends and a legend's labels.
inline std::string signedLengthText(double mm) {
    const std::string text = lengthText(mm);
    return mm > 0.0 && text != "0" ? "+" + text : text;
}

/// The significant digits and the most decimals an area is printed with (mm^2): six digits, as
/// "%.6g" printed them, down to a square micrometre.
constexpr int kAreaDigits = 6;
constexpr int kAreaDecimals = 6;

/// @brief An area (mm^2) as tables print it, without the unit and never with an exponent:
/// kAreaDigits significant digits, at most kAreaDecimals decimals, no trailing zeros.
inline std::string areaText(double mm2) { return detail::fixedText(mm2, kAreaDigits, kAreaDecimals, true); }

}  // namespace dexelmill
