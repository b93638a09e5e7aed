/// @file expressions.cpp
/// @brief Parameters (numbered, named, local) and expressions: values, operators and functions.
#include "path/gcode/interpreter.h"

#include <cmath>
#include <string>

#include "path/detail/text.h"

namespace dexelmill::detail::gcode {

double Interpreter::getParam(const ParamRef& r) {
    if (r.name.empty()) {
        switch (r.index) {
        case 5400: return double(toolInSpindle_);
        case 5420: case 5421: case 5422: {
            const Vec3 p = toProgram(mpos_);
            return p[r.index - 5420] / units_;
        }
        default: return params_[std::size_t(r.index)];
        }
    }
    if (!frames_.empty() && r.name[0] != '_') {
        auto it = frames_.back().locals.find(r.name);
        if (it != frames_.back().locals.end()) return it->second;
    }
    auto it = named_.find(r.name);
    if (it == named_.end()) fail(r.col, "named parameter not defined", "#<" + r.name + ">");
    return it->second;
}

void Interpreter::setParam(const ParamRef& r, double v) {
    if (!r.name.empty()) {
        if (!frames_.empty() && !frames_.back().fanuc && r.name[0] != '_')
            storeNamed(frames_.back().locals, r.name, v);
        else
            storeNamed(named_, r.name, v);
        return;
    }
    if (r.index == 3000)
        fail(r.col, "the program raises alarm #3000 = " + std::to_string(v), "#3000");
    store(params_[std::size_t(r.index)], v);
    for (int k = 0; k < 2; ++k) {
        const int base = k == 0 ? 5161 : 5181;  // G28's and G30's X, Y, Z
        if (r.index >= base && r.index < base + 3) homeStated_[std::size_t(k)][std::size_t(r.index - base)] = true;
    }
    // A work offset's X, Y or Z (#5221 + 20 k ..), stated here, takes effect when its system is
    // next selected (setCoordSystem); a G92 offset kept for G92.3 (#5211..) is stated too.
    if (r.index >= 5221 && r.index < 5221 + 20 * 9 && (r.index - 5221) % 20 < 3) {
        const std::size_t k = std::size_t((r.index - 5221) / 20), a = std::size_t((r.index - 5221) % 20);
        g5xParamStated_[k][a] = true;
        g5xParamGuessed_[k][a] = false;
    }
    if (r.index >= 5211 && r.index < 5214) g92StoredGuessed_[std::size_t(r.index - 5211)] = false;
}

ParamRef Interpreter::readParamRef(std::size_t& i) {
    // at '#'
    ParamRef r;
    r.col = int(i) + 1;
    ++i;
    i = skipSpaces(line_, i);
    if (i < line_.size() && line_[i] == '<') {
        const std::size_t close = line_.find('>', i);
        if (close == std::string_view::npos)
            fail(int(i) + 1, "unterminated parameter name", std::string(line_.substr(i, 40)));
        for (std::size_t t = i + 1; t < close; ++t)
            if (line_[t] != ' ' && line_[t] != '\t')
                r.name += char(std::tolower(static_cast<unsigned char>(line_[t])));
        if (r.name.empty()) fail(int(i) + 1, "empty parameter name", "#<>");
        i = close + 1;
        return r;
    }
    const double v = readRealValue(i);
    const double rounded = std::nearbyint(v);
    if (std::abs(v - rounded) > 1e-4 || rounded < 1 || rounded >= kNumParams)
        fail(r.col, "parameter number out of range (1.." + std::to_string(kNumParams - 1) + ")",
             tokenAt(r.col));
    r.index = int(rounded);
    return r;
}

double Interpreter::readRealValue(std::size_t& i) {
    i = skipSpaces(line_, i);
    if (i >= line_.size()) fail(int(i) + 1, "missing value at end of line", tokenAt(int(i)));
    const char c = line_[i];
    if (c == '[') {
        const Nesting nesting(*this, depth_, i);
        const int col = int(i) + 1;
        ++i;
        const double v = parseExpression(i, 0);
        i = skipSpaces(line_, i);
        if (i >= line_.size() || line_[i] != ']')
            fail(col, "unclosed '[' in expression", std::string(line_.substr(std::size_t(col - 1), 40)));
        ++i;
        return v;
    }
    if (c == '#') {
        ParamRef r = readParamRef(i);
        return getParam(r);
    }
    if (c == '-' || c == '+') {
        const Nesting nesting(*this, depth_, i);
        ++i;
        const double v = readRealValue(i);
        return c == '-' ? -v : v;
    }
    if ((c >= '0' && c <= '9') || c == '.') {
        double v;
        const std::size_t start = i;
        if (!detail::parseUnsignedDecimal(line_, i, v))
            fail(int(start) + 1, "bad number", tokenAt(int(start) + 1));
        if (i < line_.size() && (line_[i] == '.' ))
            fail(int(start) + 1, "bad number", tokenAt(int(start) + 1));
        return v;
    }
    if (std::isalpha(static_cast<unsigned char>(c))) return readFunction(i);
    fail(int(i) + 1, "expected a number, parameter or [expression]", tokenAt(int(i) + 1));
}

double Interpreter::readFunction(std::size_t& i) {
    const std::size_t start = i;
    std::string name;
    while (i < line_.size() && std::isalpha(static_cast<unsigned char>(line_[i])))
        name += upper(line_[i++]);
    const int col = int(start) + 1;
    i = skipSpaces(line_, i);
    if (i >= line_.size() || line_[i] != '[')
        fail(col, "expected a number (unknown word or function)", tokenAt(col));
    if (name == "EXISTS") {
        ++i;
        i = skipSpaces(line_, i);
        bool exists = false;
        if (i < line_.size() && line_[i] == '#') {
            ParamRef r = readParamRef(i);
            if (r.name.empty())
                exists = true;
            else
                exists = named_.count(r.name) ||
                         (!frames_.empty() && frames_.back().locals.count(r.name));
        }
        i = skipSpaces(line_, i);
        if (i >= line_.size() || line_[i] != ']') fail(col, "unclosed EXISTS[", tokenAt(col));
        ++i;
        return exists ? 1.0 : 0.0;
    }
    const double a = readRealValue(i);
    auto domain = [&](bool ok) {
        if (!ok) fail(col, "argument of " + name + " out of its domain", tokenAt(col, 40));
    };
    if (name == "ATAN") {
        i = skipSpaces(line_, i);
        if (i >= line_.size() || line_[i] != '/')
            fail(col, "ATAN needs the form ATAN[y]/[x]", tokenAt(col, 40));
        ++i;
        i = skipSpaces(line_, i);
        if (i >= line_.size() || line_[i] != '[')
            fail(col, "ATAN needs the form ATAN[y]/[x]", tokenAt(col, 40));
        const double x = readRealValue(i);
        return std::atan2(a, x) / kDeg;
    }
    if (name == "ABS") return std::abs(a);
    if (name == "ACOS") return domain(a >= -1 && a <= 1), std::acos(a) / kDeg;
    if (name == "ASIN") return domain(a >= -1 && a <= 1), std::asin(a) / kDeg;
    if (name == "COS") return std::cos(a * kDeg);
    if (name == "SIN") return std::sin(a * kDeg);
    if (name == "TAN") return std::tan(a * kDeg);
    if (name == "EXP") return std::exp(a);
    if (name == "FIX") return std::floor(a);
    if (name == "FUP") return std::ceil(a);
    if (name == "ROUND") return std::round(a);
    if (name == "LN") return domain(a > 0), std::log(a);
    if (name == "SQRT") return domain(a >= 0), std::sqrt(a);
    fail(col, "unknown function " + name, tokenAt(col));
}

int Interpreter::peekOperator(std::size_t i, int& code, std::size_t& len) {
    i = skipSpaces(line_, i);
    if (i >= line_.size()) return 0;
    const char c = line_[i];
    len = 1;
    if (c == '*' && i + 1 < line_.size() && line_[i + 1] == '*') { len = 2; code = 'P'; return 5; }
    if (c == '*') { code = '*'; return 4; }
    if (c == '/') { code = '/'; return 4; }
    if (c == '+') { code = '+'; return 3; }
    if (c == '-') { code = '-'; return 3; }
    if (!std::isalpha(static_cast<unsigned char>(c))) return 0;
    char w[4] = {0, 0, 0, 0};
    std::size_t n = 0;
    while (n < 3 && i + n < line_.size() && std::isalpha(static_cast<unsigned char>(line_[i + n])))
        w[n] = upper(line_[i + n]), ++n;
    const std::string_view word(w, n);
    len = n;
    struct Op { const char* name; int code; int prec; };
    static const Op ops[] = {{"MOD", 'M', 4}, {"EQ", 'e', 2}, {"NE", 'n', 2}, {"GT", 'g', 2},
                             {"GE", 'G', 2},  {"LT", 'l', 2}, {"LE", 'L', 2}, {"AND", '&', 1},
                             {"OR", '|', 1},  {"XOR", '^', 1}};
    for (const Op& op : ops) {
        const std::string_view name(op.name);
        if (word.substr(0, name.size()) == name) {
            len = name.size();
            code = op.code;
            return op.prec;
        }
    }
    return 0;
}

double Interpreter::parseExpression(std::size_t& i, int minPrec) {
    double lhs = readRealValue(i);
    while (true) {
        int code = 0;
        std::size_t len = 0;
        const int prec = peekOperator(i, code, len);
        if (prec == 0 || prec <= minPrec) {
            if (prec == 0) {
                const std::size_t j = skipSpaces(line_, i);
                if (j < line_.size() && line_[j] != ']')
                    fail(int(j) + 1, "expected an operator or ']'", tokenAt(int(j) + 1));
            }
            return lhs;
        }
        i = skipSpaces(line_, i);
        const int opCol = int(i) + 1;
        i += len;
        // ** is right-associative, so a chain of them recurses once per operator and counts a
        // level each; the others are left-associative and recurse at most once per precedence.
        double rhs;
        if (code == 'P') {
            const Nesting nesting(*this, depth_, i);
            rhs = parseExpression(i, prec - 1);
        } else {
            rhs = parseExpression(i, prec);
        }
        switch (code) {
        case 'P': lhs = std::pow(lhs, rhs); break;
        case '*': lhs *= rhs; break;
        case '/':
            if (rhs == 0.0) fail(opCol, "division by zero", std::string(line_.substr(std::size_t(opCol - 1), 24)));
            lhs /= rhs;
            break;
        case 'M':
            if (rhs == 0.0) fail(opCol, "MOD by zero", std::string(line_.substr(std::size_t(opCol - 1), 24)));
            lhs = lhs - std::floor(lhs / rhs) * rhs;
            break;
        case '+': lhs += rhs; break;
        case '-': lhs -= rhs; break;
        case 'e': lhs = lhs == rhs; break;
        case 'n': lhs = lhs != rhs; break;
        case 'g': lhs = lhs > rhs; break;
        case 'G': lhs = lhs >= rhs; break;
        case 'l': lhs = lhs < rhs; break;
        case 'L': lhs = lhs <= rhs; break;
        case '&': lhs = (lhs != 0.0) && (rhs != 0.0); break;
        case '|': lhs = (lhs != 0.0) || (rhs != 0.0); break;
        case '^': lhs = (lhs != 0.0) != (rhs != 0.0); break;
        }
        if (!std::isfinite(lhs)) fail(opCol, "expression overflows", std::string(line_.substr(std::size_t(opCol - 1), 24)));
    }
}

}  // namespace dexelmill::detail::gcode
