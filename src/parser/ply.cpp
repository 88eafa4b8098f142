#include "parser/ply.h"

#include "core/provenance.h"

#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>

#include "core/error.h"

namespace gradus {

namespace {

enum class PType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool ParsePType(const std::string &s, PType *t) {
    static const struct { const char *name; PType t; } table[] = {
        {"char", PType::Int8},     {"int8", PType::Int8},     {"uchar", PType::UInt8},   {"uint8", PType::UInt8},
        {"short", PType::Int16},   {"int16", PType::Int16},   {"ushort", PType::UInt16}, {"uint16", PType::UInt16},
        {"int", PType::Int32},     {"int32", PType::Int32},   {"uint", PType::UInt32},   {"uint32", PType::UInt32},
        {"float", PType::Float32}, {"float32", PType::Float32}, {"double", PType::Float64},
        {"float64", PType::Float64},
    };
    for (const auto &e : table)
        if (s == e.name) {
            *t = e.t;
            return true;
        }
    return false;
}

size_t PTypeSize(PType t) {
    switch (t) {
        case PType::Int8: case PType::UInt8: return 1;
        case PType::Int16: case PType::UInt16: return 2;
        case PType::Int32: case PType::UInt32: case PType::Float32: return 4;
        default: return 8;
    }
}

bool IsIntegral(PType t) { return t != PType::Float32 && t != PType::Float64; }

struct Property {
    std::string name;
    PType type = PType::Float32;
    bool isList = false;
    PType countType = PType::UInt8;
};

struct Element {
    std::string name;
    uint64_t count = 0;
    std::vector<Property> props;
};

enum class Format { Ascii, BinaryLE, BinaryBE };

// Sequential value reader over the body of the file.
class BodyReader {
  public:
    BodyReader(const char *data, size_t size, Format f, const std::string &name)
        : p_(data), end_(data + size), format_(f), name_(name) {}

    // Reads one value of type t as double; throws at end of data.
    double read(PType t, const std::string &where) {
        if (format_ == Format::Ascii) return readAscii(t, where);
        size_t n = PTypeSize(t);
        if (size_t(end_ - p_) < n) truncated(where);
        unsigned char b[8];
        std::memcpy(b, p_, n);
        p_ += n;
        if (format_ == Format::BinaryBE)
            for (size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
        switch (t) {
            case PType::Int8: { int8_t v; std::memcpy(&v, b, 1); return v; }
            case PType::UInt8: return b[0];
            case PType::Int16: { int16_t v; std::memcpy(&v, b, 2); return v; }
            case PType::UInt16: { uint16_t v; std::memcpy(&v, b, 2); return v; }
            case PType::Int32: { int32_t v; std::memcpy(&v, b, 4); return v; }
            case PType::UInt32: { uint32_t v; std::memcpy(&v, b, 4); return v; }
            case PType::Float32: { float v; std::memcpy(&v, b, 4); return v; }
            default: { double v; std::memcpy(&v, b, 8); return v; }
        }
    }

    // Skips `count` values of type t.
    void skip(PType t, uint64_t count, const std::string &where) {
        if (format_ == Format::Ascii) {
            for (uint64_t i = 0; i < count; ++i) readAscii(t, where);
            return;
        }
        uint64_t bytes = count * PTypeSize(t);
        if (count > uint64_t(end_ - p_) || uint64_t(end_ - p_) < bytes) truncated(where);
        p_ += bytes;
    }

    size_t remaining() const { return size_t(end_ - p_); }

  private:
    [[noreturn]] void truncated(const std::string &where) const {
        throw Error(name_ + ": truncated PLY file (unexpected end of data in " + where + ")");
    }

    double readAscii(PType t, const std::string &where) {
        while (p_ < end_ && std::isspace(static_cast<unsigned char>(*p_))) ++p_;
        if (p_ == end_) truncated(where);
        const char *s = p_;
        while (p_ < end_ && !std::isspace(static_cast<unsigned char>(*p_))) ++p_;
        const char *b = s;
        if (*b == '+') ++b;
        double v;
        auto r = std::from_chars(b, p_, v);
        if (b == p_ || r.ec != std::errc() || r.ptr != p_)
            throw Error(name_ + ": malformed number '" + std::string(s, std::min<size_t>(p_ - s, 40)) + "' in " +
                        where);
        if (IsIntegral(t) && v != std::floor(v))
            throw Error(name_ + ": non-integer value '" + std::string(s, std::min<size_t>(p_ - s, 40)) +
                        "' for an integer property in " + where);
        return v;
    }

    const char *p_, *end_;
    Format format_;
    const std::string &name_;
};

bool NextLine(const char *data, size_t size, size_t *pos, std::string *line) {
    if (*pos >= size) return false;
    const char *s = data + *pos;
    const void *nl = std::memchr(s, '\n', size - *pos);
    size_t len = nl ? size_t(static_cast<const char *>(nl) - s) : size - *pos;
    *pos += len + (nl ? 1 : 0);
    if (len > 0 && s[len - 1] == '\r') --len;
    line->assign(s, len);
    return true;
}

// "name:line: msg" (line > 0) or "name: msg".
Error PlyError(const std::string &name, int line, const std::string &msg) {
    return Error(name + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + msg);
}

struct Header {
    Format format = Format::Ascii;
    std::vector<Element> elements;
    size_t bodyStart = 0;  // offset of the first byte after end_header's line
};

// "property TYPE NAME" or "property list COUNTTYPE TYPE NAME" (after the keyword).
Property ParsePropertyLine(std::istringstream &ss, const std::string &name, int lineNo) {
    Property p;
    std::string t;
    if (!(ss >> t)) throw PlyError(name, lineNo, "malformed property line");
    if (t == "list") {
        std::string ct, it;
        if (!(ss >> ct >> it >> p.name)) throw PlyError(name, lineNo, "malformed list property line");
        if (!ParsePType(ct, &p.countType) || !IsIntegral(p.countType))
            throw PlyError(name, lineNo, "bad list count type '" + ct + "'");
        if (!ParsePType(it, &p.type)) throw PlyError(name, lineNo, "unknown property type '" + it + "'");
        p.isList = true;
    } else {
        if (!ParsePType(t, &p.type)) throw PlyError(name, lineNo, "unknown property type '" + t + "'");
        if (!(ss >> p.name)) throw PlyError(name, lineNo, "malformed property line");
    }
    return p;
}

// "element NAME COUNT" (after the keyword).
Element ParseElementLine(std::istringstream &ss, const std::string &name, int lineNo) {
    Element e;
    std::string count;
    if (!(ss >> e.name >> count)) throw PlyError(name, lineNo, "malformed element line");
    auto r = std::from_chars(count.data(), count.data() + count.size(), e.count);
    if (r.ec != std::errc() || r.ptr != count.data() + count.size())
        throw PlyError(name, lineNo, "malformed element count '" + count + "'");
    return e;
}

Header ParseHeader(const char *data, size_t size, const std::string &name) {
    Header h;
    size_t pos = 0;
    std::string line;
    int lineNo = 0;
    if (!NextLine(data, size, &pos, &line) || line != "ply")
        throw PlyError(name, 1, "not a PLY file (missing 'ply' magic)");
    ++lineNo;
    bool haveFormat = false, haveEnd = false;
    while (NextLine(data, size, &pos, &line)) {
        ++lineNo;
        std::istringstream ss(line);
        std::string kw;
        if (!(ss >> kw)) continue;
        if (kw == "comment" || kw == "obj_info") continue;
        if (kw == "end_header") {
            haveEnd = true;
            break;
        }
        if (kw == "format") {
            std::string f, version;
            if (!(ss >> f >> version)) throw PlyError(name, lineNo, "malformed format line");
            if (f == "ascii") h.format = Format::Ascii;
            else if (f == "binary_little_endian") h.format = Format::BinaryLE;
            else if (f == "binary_big_endian") h.format = Format::BinaryBE;
            else throw PlyError(name, lineNo, "unknown PLY format '" + f + "'");
            haveFormat = true;
        } else if (kw == "element") {
            h.elements.push_back(ParseElementLine(ss, name, lineNo));
        } else if (kw == "property") {
            if (h.elements.empty()) throw PlyError(name, lineNo, "property before any element");
            h.elements.back().props.push_back(ParsePropertyLine(ss, name, lineNo));
        } else {
            throw PlyError(name, lineNo, "unknown header keyword '" + kw + "'");
        }
    }
    if (!haveEnd) throw PlyError(name, 0, "truncated PLY header (no end_header)");
    if (!haveFormat) throw PlyError(name, 0, "PLY header has no format line");
    h.bodyStart = pos;
    return h;
}

// Reads a list's count and skips its entries.
void SkipList(BodyReader &in, const Property &p, const std::string &where, const std::string &name) {
    double c = in.read(p.countType, where);
    if (!(c >= 0)) throw PlyError(name, 0, "negative list length in " + where);
    in.skip(p.type, uint64_t(c), where);
}

// Positions, and normals and uv when the element has them all.
void ReadVertices(const Element &e, Format format, BodyReader &in, const std::string &name, PlyMesh &mesh) {
    const std::string where = "element '" + e.name + "'";
    if (e.count > uint64_t(INT_MAX)) throw PlyError(name, 0, "too many vertices (" + std::to_string(e.count) + ")");
    int ix = -1, iy = -1, iz = -1, inx = -1, iny = -1, inz = -1, iu = -1, iv = -1;
    for (int i = 0; i < int(e.props.size()); ++i) {
        const std::string &n = e.props[i].name;
        if (e.props[i].isList) continue;
        if (n == "x") ix = i;
        else if (n == "y") iy = i;
        else if (n == "z") iz = i;
        else if (n == "nx") inx = i;
        else if (n == "ny") iny = i;
        else if (n == "nz") inz = i;
        else if (n == "u" || n == "s" || n == "texture_u" || n == "texture_s") iu = i;
        else if (n == "v" || n == "t" || n == "texture_v" || n == "texture_t") iv = i;
    }
    if (ix < 0 || iy < 0 || iz < 0) throw PlyError(name, 0, "vertex element lacks x, y or z");
    bool hasN = inx >= 0 && iny >= 0 && inz >= 0, hasUV = iu >= 0 && iv >= 0;
    // Reserve no more than the data could possibly hold.
    size_t cap = std::min<uint64_t>(e.count, in.remaining() / (format == Format::Ascii ? 2 : 1) + 1);
    mesh.P.reserve(cap);
    if (hasN) mesh.N.reserve(cap);
    if (hasUV) mesh.uv.reserve(cap);
    std::vector<double> vals(e.props.size());
    for (uint64_t r = 0; r < e.count; ++r) {
        for (size_t i = 0; i < e.props.size(); ++i) {
            const Property &p = e.props[i];
            if (p.isList) {
                SkipList(in, p, where, name);
                vals[i] = 0;
            } else {
                vals[i] = in.read(p.type, where);
            }
        }
        mesh.P.emplace_back(vals[ix], vals[iy], vals[iz]);
        if (hasN) mesh.N.emplace_back(vals[inx], vals[iny], vals[inz]);
        if (hasUV) mesh.uv.emplace_back(vals[iu], vals[iv]);
    }
}

// Face r's vertex_indices list of c entries: a triangle, or a quad as two.
void ReadFaceIndices(BodyReader &in, const Property &p, uint64_t r, double c, const std::string &where,
                     const std::string &name, PlyMesh &mesh) {
    if (c != 3 && c != 4)
        throw PlyError(name, 0, "face " + std::to_string(r) + " has " + std::to_string(int64_t(c)) +
                                    " vertices (only triangles and quads are supported)");
    int v[4];
    for (int k = 0; k < int(c); ++k) {
        double x = in.read(p.type, where);
        if (!(x >= 0 && x <= double(INT_MAX)))
            throw PlyError(name, 0, "face " + std::to_string(r) + ": vertex index " + std::to_string(int64_t(x)) +
                                        " out of range");
        v[k] = int(x);
    }
    mesh.indices.insert(mesh.indices.end(), {v[0], v[1], v[2]});
    if (c == 4) mesh.indices.insert(mesh.indices.end(), {v[0], v[2], v[3]});
}

void ReadFaces(const Element &e, BodyReader &in, const std::string &name, PlyMesh &mesh) {
    const std::string where = "element '" + e.name + "'";
    int iIdx = -1;
    for (int i = 0; i < int(e.props.size()); ++i)
        if (e.props[i].isList && (e.props[i].name == "vertex_indices" || e.props[i].name == "vertex_index"))
            iIdx = i;
    if (iIdx < 0) throw PlyError(name, 0, "face element has no vertex_indices list");
    if (!IsIntegral(e.props[iIdx].type)) throw PlyError(name, 0, "vertex_indices must have an integer type");
    size_t cap = std::min<uint64_t>(e.count, in.remaining() / 4 + 1);
    mesh.indices.reserve(cap * 3);
    for (uint64_t r = 0; r < e.count; ++r) {
        for (int i = 0; i < int(e.props.size()); ++i) {
            const Property &p = e.props[i];
            if (!p.isList) {
                in.read(p.type, where);
            } else if (i != iIdx) {
                SkipList(in, p, where, name);
            } else {
                double c = in.read(p.countType, where);
                if (!(c >= 0)) throw PlyError(name, 0, "negative list length in " + where);
                ReadFaceIndices(in, p, r, c, where, name, mesh);
            }
        }
    }
}

void SkipElement(const Element &e, BodyReader &in, const std::string &name) {
    const std::string where = "element '" + e.name + "'";
    for (uint64_t r = 0; r < e.count; ++r)
        for (const Property &p : e.props) {
            if (p.isList) SkipList(in, p, where, name);
            else in.read(p.type, where);
        }
}

}  // namespace

PlyMesh ReadPlyFromMemory(const char *data, size_t size, const std::string &name) {
    const Header h = ParseHeader(data, size, name);
    PlyMesh mesh;
    BodyReader in(data + h.bodyStart, size - h.bodyStart, h.format, name);
    bool haveVertices = false;
    uint64_t nVertices = 0;
    for (const Element &e : h.elements) {
        if (e.props.empty()) continue;  // nothing stored per record
        if (e.name == "vertex") {
            if (haveVertices) throw PlyError(name, 0, "more than one vertex element");
            haveVertices = true;
            ReadVertices(e, h.format, in, name, mesh);
            nVertices = e.count;
        } else if (e.name == "face") {
            ReadFaces(e, in, name, mesh);
        } else {
            SkipElement(e, in, name);
        }
    }
    if (!haveVertices) throw PlyError(name, 0, "PLY file has no vertex element");
    for (size_t i = 0; i < mesh.indices.size(); ++i)
        if (uint64_t(mesh.indices[i]) >= nVertices)
            throw PlyError(name, 0, "triangle " + std::to_string(i / 3) + " references vertex " +
                                        std::to_string(mesh.indices[i]) + " but there are only " +
                                        std::to_string(nVertices) + " vertices");
    return mesh;
}

PlyMesh ReadPly(const std::string &filename) {
    std::string data;
    switch (ReadFileBytes(filename, &data)) {
    case FileRead::CannotOpen: throw Error(filename + ": cannot open PLY file");
    case FileRead::ReadError: throw Error(filename + ": error reading PLY file");
    case FileRead::Ok: break;
    }
    RecordInputFile(filename, data.data(), data.size());  // provenance: meshes are scene inputs
    return ReadPlyFromMemory(data.data(), data.size(), filename);
}

}  // namespace gradus
