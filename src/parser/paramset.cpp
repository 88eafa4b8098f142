#include "parser/paramset.h"

#include <cmath>
#include <cstdio>
#include <cstring>

namespace gradus {

namespace {

std::string Num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

std::string Describe(const Param &p) { return "\"" + p.type + " " + p.name + "\""; }

[[noreturn]] void CountError(const Param &p, const std::string &want) {
    size_t n = p.numbers.size() + p.strings.size() + p.bools.size();
    throw Error(p.loc, "parameter " + Describe(p) + " needs " + want + ", got " + std::to_string(n) + " value" +
                           (n == 1 ? "" : "s"));
}

}  // namespace

std::string ParamSet::canonicalType(const std::string &t) {
    if (t == "point") return "point3";
    if (t == "vector") return "vector3";
    if (t == "normal") return "normal3";
    if (t == "color") return "rgb";
    return t;
}

void ParamSet::add(Param p) {
    for (auto &q : params_)
        if (q.name == p.name) {
            q = std::move(p);
            return;
        }
    params_.push_back(std::move(p));
}

const Param *ParamSet::find(const std::string &name) const {
    for (const auto &p : params_)
        if (p.name == name) {
            p.used = true;
            return &p;
        }
    return nullptr;
}

const Param *ParamSet::lookup(const std::string &name, std::initializer_list<const char *> types,
                              const char *expected) const {
    const Param *p = find(name);
    if (!p) return nullptr;
    std::string t = canonicalType(p->type);
    for (const char *ok : types)
        if (t == ok) return p;
    throw Error(p->loc, "parameter " + Describe(*p) + " has type " + p->type + ", expected " + expected);
}


// ---- resolved values (provenance)

void ParamSet::note(const char *type, const std::string &name, const std::string &value) const {
    for (const auto &r : resolved_)
        if (r.first == name) return;
    resolved_.push_back({name, "\"" + std::string(type) + " " + name + "\" " + value});
}

std::string ParamSet::resolved() const {
    std::string out;
    for (const auto &r : resolved_) out += (out.empty() ? "" : " ") + r.second;
    return out;
}

int ParamSet::getInt(const std::string &name, int def) const {
    int v = getIntRaw(name, def);
    note("integer", name, std::to_string(v));
    return v;
}

Float ParamSet::getFloat(const std::string &name, Float def) const {
    Float v = getFloatRaw(name, def);
    if (std::isfinite(v)) note("float", name, Num(v));  // an infinite default means "none" and is not scene syntax
    return v;
}

bool ParamSet::getBool(const std::string &name, bool def) const {
    bool v = getBoolRaw(name, def);
    note("bool", name, std::string(v ? "\"true\"" : "\"false\""));
    return v;
}

std::string ParamSet::getString(const std::string &name, const std::string &def) const {
    std::string v = getStringRaw(name, def);
    note("string", name, "\"" + v + "\"");
    return v;
}

Point2 ParamSet::getPoint2(const std::string &name, Point2 def) const {
    Point2 v = getPoint2Raw(name, def);
    note("point2", name, "[" + Num(v.x) + " " + Num(v.y) + "]");
    return v;
}

Point3 ParamSet::getPoint3(const std::string &name, Point3 def) const {
    Point3 v = getPoint3Raw(name, def);
    note("point3", name, "[" + Num(v.x) + " " + Num(v.y) + " " + Num(v.z) + "]");
    return v;
}

Vec3 ParamSet::getVector3(const std::string &name, Vec3 def) const {
    Vec3 v = getVector3Raw(name, def);
    note("vector3", name, "[" + Num(v.x) + " " + Num(v.y) + " " + Num(v.z) + "]");
    return v;
}

Normal3 ParamSet::getNormal(const std::string &name, Normal3 def) const {
    Normal3 v = getNormalRaw(name, def);
    note("normal", name, "[" + Num(v.x) + " " + Num(v.y) + " " + Num(v.z) + "]");
    return v;
}

Spectrum ParamSet::getSpectrum(const std::string &name, Spectrum def, SpectrumKind kind) const {
    Spectrum v = getSpectrumRaw(name, def, kind);
    note("rgb", name, "[" + Num(v.r) + " " + Num(v.g) + " " + Num(v.b) + "]");
    return v;
}

// Lists are recorded when given, at most 16 values.
template <typename T, typename Fmt>
std::string ListText(const std::vector<T> &v, Fmt fmt) {
    std::string t = "[";
    for (size_t i = 0; i < v.size() && i < 16; ++i) t += std::string(i ? " " : "") + fmt(v[i]);
    return t + (v.size() > 16 ? " ...]" : "]");
}

std::vector<int> ParamSet::getInts(const std::string &name) const {
    std::vector<int> v = getIntsRaw(name);
    if (!v.empty()) note("integer", name, ListText(v, [](int x) { return std::to_string(x); }));
    return v;
}

std::vector<Float> ParamSet::getFloats(const std::string &name) const {
    std::vector<Float> v = getFloatsRaw(name);
    if (!v.empty()) note("float", name, ListText(v, [](Float x) { return Num(x); }));
    return v;
}

std::vector<std::string> ParamSet::getStrings(const std::string &name) const {
    std::vector<std::string> v = getStringsRaw(name);
    if (!v.empty()) note("string", name, ListText(v, [](const std::string &x) { return "\"" + x + "\""; }));
    return v;
}

int ParamSet::getIntRaw(const std::string &name, int def) const {
    const Param *p = lookup(name, {"integer"}, "integer");
    if (!p) return def;
    if (p->numbers.size() != 1) CountError(*p, "1 value");
    return static_cast<int>(p->numbers[0]);
}

Float ParamSet::getFloatRaw(const std::string &name, Float def) const {
    const Param *p = lookup(name, {"float", "integer"}, "float");
    if (!p) return def;
    if (p->numbers.size() != 1) CountError(*p, "1 value");
    return p->numbers[0];
}

bool ParamSet::getBoolRaw(const std::string &name, bool def) const {
    const Param *p = lookup(name, {"bool"}, "bool");
    if (!p) return def;
    if (p->bools.size() != 1) CountError(*p, "1 value");
    return p->bools[0];
}

std::string ParamSet::getStringRaw(const std::string &name, const std::string &def) const {
    const Param *p = lookup(name, {"string"}, "string");
    if (!p) return def;
    if (p->strings.size() != 1) CountError(*p, "1 value");
    return p->strings[0];
}

Point2 ParamSet::getPoint2Raw(const std::string &name, Point2 def) const {
    const Param *p = lookup(name, {"point2"}, "point2");
    if (!p) return def;
    if (p->numbers.size() != 2) CountError(*p, "2 values");
    return {p->numbers[0], p->numbers[1]};
}

Point3 ParamSet::getPoint3Raw(const std::string &name, Point3 def) const {
    const Param *p = lookup(name, {"point3"}, "point3");
    if (!p) return def;
    if (p->numbers.size() != 3) CountError(*p, "3 values");
    return {p->numbers[0], p->numbers[1], p->numbers[2]};
}

Vec3 ParamSet::getVector3Raw(const std::string &name, Vec3 def) const {
    const Param *p = lookup(name, {"vector3"}, "vector3");
    if (!p) return def;
    if (p->numbers.size() != 3) CountError(*p, "3 values");
    return {p->numbers[0], p->numbers[1], p->numbers[2]};
}

Normal3 ParamSet::getNormalRaw(const std::string &name, Normal3 def) const {
    const Param *p = lookup(name, {"normal3"}, "normal3");
    if (!p) return def;
    if (p->numbers.size() != 3) CountError(*p, "3 values");
    return {p->numbers[0], p->numbers[1], p->numbers[2]};
}

Spectrum ParamSet::getSpectrum(const std::string &name, Spectrum def) const {
    return getSpectrum(name, def, SpectrumKind::Reflectance);
}

Spectrum ParamSet::getSpectrumRaw(const std::string &name, Spectrum def, SpectrumKind kind) const {
    const Param *p = lookup(name, {"rgb", "spectrum", "blackbody"}, "rgb, color, spectrum or blackbody");
    if (!p) return def;
    std::string t = canonicalType(p->type);
    if (t == "rgb") {
        if (p->numbers.size() != 3) CountError(*p, "3 values");
        return {p->numbers[0], p->numbers[1], p->numbers[2]};
    }
    if (t == "blackbody") {
        if (p->numbers.size() != 2) CountError(*p, "2 values (temperature in K, scale)");
        return BlackbodyToRGB(p->numbers[0], p->numbers[1]);
    }
    // spectrum
    if (!p->strings.empty()) {
        // Filenames were loaded into numbers by the parser; what is left is a
        // named spectrum, which Gradus does not tabulate.
        throw UnsupportedError(p->loc, "named spectrum \"" + p->strings[0] + "\"");
    }
    if (p->numbers.size() < 2 || p->numbers.size() % 2 != 0)
        CountError(*p, "(wavelength value) pairs");
    std::vector<double> lambda, values;
    for (size_t i = 0; i < p->numbers.size(); i += 2) {
        lambda.push_back(p->numbers[i]);
        values.push_back(p->numbers[i + 1]);
    }
    return SampledToRGB(lambda, values, kind);
}

std::string ParamSet::getTexture(const std::string &name) const {
    // A parameter of another type under this name (e.g. "rgb Kd") is not a
    // texture reference: report absent and leave it for the typed lookup.
    for (const auto &p : params_)
        if (p.name == name) {
            if (p.type != "texture") return "";
            p.used = true;
            if (p.strings.size() != 1) CountError(p, "1 value");
            return p.strings[0];
        }
    return "";
}

std::vector<int> ParamSet::getIntsRaw(const std::string &name) const {
    const Param *p = lookup(name, {"integer"}, "integer");
    if (!p) return {};
    std::vector<int> r;
    r.reserve(p->numbers.size());
    for (double v : p->numbers) r.push_back(static_cast<int>(v));
    return r;
}

std::vector<Float> ParamSet::getFloatsRaw(const std::string &name) const {
    const Param *p = lookup(name, {"float", "integer"}, "float");
    if (!p) return {};
    return p->numbers;
}

std::vector<Point2> ParamSet::getPoint2s(const std::string &name) const {
    const Param *p = lookup(name, {"point2", "float"}, "point2 (or float pairs)");
    if (!p) return {};
    if (p->numbers.size() % 2 != 0) CountError(*p, "a multiple of 2 values");
    std::vector<Point2> r(p->numbers.size() / 2);
    for (size_t i = 0; i < r.size(); ++i) r[i] = {p->numbers[2 * i], p->numbers[2 * i + 1]};
    return r;
}

namespace {
std::vector<Vec3> Triples(const Param &p) {
    if (p.numbers.size() % 3 != 0) CountError(p, "a multiple of 3 values");
    std::vector<Vec3> r(p.numbers.size() / 3);
    for (size_t i = 0; i < r.size(); ++i) r[i] = {p.numbers[3 * i], p.numbers[3 * i + 1], p.numbers[3 * i + 2]};
    return r;
}
}  // namespace

std::vector<Point3> ParamSet::getPoint3s(const std::string &name) const {
    const Param *p = lookup(name, {"point3"}, "point3");
    return p ? Triples(*p) : std::vector<Point3>{};
}

std::vector<Normal3> ParamSet::getNormals(const std::string &name) const {
    const Param *p = lookup(name, {"normal3"}, "normal3");
    return p ? Triples(*p) : std::vector<Normal3>{};
}

std::vector<Vec3> ParamSet::getVector3s(const std::string &name) const {
    const Param *p = lookup(name, {"vector3"}, "vector3");
    return p ? Triples(*p) : std::vector<Vec3>{};
}

std::vector<std::string> ParamSet::getStringsRaw(const std::string &name) const {
    const Param *p = lookup(name, {"string"}, "string");
    return p ? p->strings : std::vector<std::string>{};
}

FileLoc ParamSet::locOf(const std::string &name, const FileLoc &fallback) const {
    for (const auto &p : params_)
        if (p.name == name) return p.loc;
    return fallback;
}

void ParamSet::checkUnused(const std::string &what) const {
    for (const auto &p : params_)
        if (!p.used)
            throw Error(p.loc, "parameter " + Describe(p) + " is not used by " + what +
                                   " (misspelt or unsupported)");
}

}  // namespace gradus
