#include "render/params.h"

#include <algorithm>
#include <cstdio>

namespace gradus {

const char *ParamInfo::typeName() const {
    switch (kind) {
    case ParamKind::Bool: return "bool";
    case ParamKind::Int:
    case ParamKind::IntList: return "integer";
    case ParamKind::Float: return "float";
    case ParamKind::String:
    case ParamKind::Enum: return "string";
    }
    return "?";
}

std::string Range::text() const {
    using params_detail::Number;
    const double inf = std::numeric_limits<double>::infinity();
    if (lo == hi) return Number(lo);
    if (lo == -inf) return hi == inf ? "" : "<= " + Number(hi);
    if (hi == inf) return ">= " + Number(lo);
    return "in [" + Number(lo) + ", " + Number(hi) + "]";
}

namespace params_detail {

std::string Number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

std::string Quote(const std::string &s) { return "\"" + s + "\""; }

void RangeError(const FileLoc &loc, const std::string &name, const Range &r) {
    throw Error(loc, Quote(name) + " must be " + r.text() + (r.why.empty() ? "" : ": " + r.why));
}

void ChoiceError(const FileLoc &loc, const std::string &name, const std::string &value, const std::string &reason,
                 const std::vector<std::string> &valid) {
    std::string list;
    for (const auto &v : valid) list += (list.empty() ? "" : ", ") + v;
    std::string what = Quote(name) + " " + Quote(value);
    throw Error(loc, (reason.empty() ? "unknown " + what : what + " " + reason) + " (valid: " + list + ")");
}

}  // namespace params_detail

std::string FormatParams(const std::vector<ParamInfo> &params) {
    size_t wName = 4, wDefault = 7;
    for (const auto &p : params) {
        wName = std::max(wName, p.name.size());
        wDefault = std::max(wDefault, p.defaultText.size());
    }
    auto pad = [](const std::string &s, size_t w) { return s + std::string(w > s.size() ? w - s.size() : 0, ' '); };
    auto line = [&](const std::string &name, const std::string &type, const std::string &def, const std::string &help) {
        return "    " + pad(name, wName) + "  " + pad(type, 7) + "  " + pad(def, wDefault) + "  " + help + "\n";
    };
    std::string out = line("name", "type", "default", "help"), group;
    for (const auto &p : params) {
        if (p.group != group) {
            group = p.group;
            out += "  " + group + ":\n";
        }
        out += line(p.name, p.typeName(), p.defaultText, p.help);
        if (!p.values.empty()) out += line("", "", "", "values: " + p.values);
    }
    return out;
}

}  // namespace gradus
