// pbrt-v3 scene parser: tokenizer, parameter lists and the graphics-state
// layer (transform stack, attributes, named materials/media/coordinate
// systems, object instancing), following the semantics of pbrt-v3's api.cpp.
#include <array>
#include <charconv>
#include <cmath>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string_view>

#include "core/provenance.h"
#include "parser/gltf.h"
#include "parser/scene_desc.h"

namespace gradus {

namespace {

// ---------------------------------------------------------------- files

bool ReadWholeFile(const std::string &path, std::string *out) {
    if (ReadFileBytes(path, out) != FileRead::Ok) return false;
    RecordInputFile(path, out->data(), out->size());  // every scene file read is part of the provenance
    return true;
}

bool IsAbsolute(const std::string &f) { return !f.empty() && f[0] == '/'; }

std::string DirectoryOf(const std::string &path) {
    size_t s = path.find_last_of('/');
    if (s == std::string::npos) return ".";
    if (s == 0) return "/";
    return path.substr(0, s);
}

std::string JoinPath(const std::string &dir, const std::string &f) {
    if (IsAbsolute(f) || dir.empty() || dir == ".") return f;
    if (dir.back() == '/') return dir + f;
    return dir + "/" + f;
}

// ---------------------------------------------------------------- tokens

enum class Tok { Word, String, LBracket, RBracket, End };

struct Token {
    Tok kind = Tok::End;
    std::string_view text;  // for strings: between the quotes, escapes not yet processed
    bool escaped = false;   // string contains a backslash escape
    int file = 0;           // index into Parser::files_
    int line = 1, column = 1;
};

class Lexer {
  public:
    Lexer(std::string text, int fileIndex, std::string dir)
        : text_(std::move(text)), file_(fileIndex), dir_(std::move(dir)) {}
    const std::string &dir() const { return dir_; }

    // Returns the next token; kind End at end of input. Throws on an
    // unterminated string (message built by the caller via `fail`).
    template <typename Fail>
    Token next(Fail &&fail) {
        const char *s = text_.data();
        const size_t n = text_.size();
        for (;;) {
            if (pos_ >= n) {
                Token t;
                t.kind = Tok::End;
                t.file = file_;
                t.line = line_;
                t.column = col_;
                return t;
            }
            char c = s[pos_];
            if (c == '\n') {
                ++pos_;
                ++line_;
                col_ = 1;
            } else if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
                ++pos_;
                ++col_;
            } else if (c == '#') {
                while (pos_ < n && s[pos_] != '\n') ++pos_;
            } else {
                break;
            }
        }
        Token t;
        t.file = file_;
        t.line = line_;
        t.column = col_;
        char c = s[pos_];
        if (c == '[' || c == ']') {
            t.kind = c == '[' ? Tok::LBracket : Tok::RBracket;
            t.text = std::string_view(s + pos_, 1);
            ++pos_;
            ++col_;
            return t;
        }
        if (c == '"') {
            size_t start = ++pos_;
            ++col_;
            for (;;) {
                if (pos_ >= n || s[pos_] == '\n') fail(t, "unterminated string");
                char d = s[pos_];
                if (d == '"') break;
                if (d == '\\') {
                    t.escaped = true;
                    if (pos_ + 1 >= n || s[pos_ + 1] == '\n') fail(t, "unterminated string");
                    pos_ += 2;
                    col_ += 2;
                } else {
                    ++pos_;
                    ++col_;
                }
            }
            t.kind = Tok::String;
            t.text = std::string_view(s + start, pos_ - start);
            ++pos_;
            ++col_;
            return t;
        }
        size_t start = pos_;
        while (pos_ < n) {
            char d = s[pos_];
            if (d == ' ' || d == '\n' || d == '\t' || d == '\r' || d == '\f' || d == '\v' || d == '"' ||
                d == '[' || d == ']' || d == '#')
                break;
            ++pos_;
        }
        col_ += static_cast<int>(pos_ - start);
        t.kind = Tok::Word;
        t.text = std::string_view(s + start, pos_ - start);
        return t;
    }

  private:
    std::string text_;
    int file_;
    std::string dir_;
    size_t pos_ = 0;
    int line_ = 1, col_ = 1;
};

// ---------------------------------------------------------------- directives

enum class Dir {
    Unknown, Camera, Film, Sampler, PixelFilter, Integrator, Accelerator, LookAt, Translate, Rotate, Scale,
    Transform, ConcatTransform, CoordinateSystem, CoordSysTransform, ActiveTransform, TransformTimes,
    Identity, ReverseOrientation, WorldBegin, WorldEnd, AttributeBegin, AttributeEnd, TransformBegin,
    TransformEnd, ObjectBegin, ObjectEnd, ObjectInstance, Material, MakeNamedMaterial, NamedMaterial,
    Texture, LightSource, AreaLightSource, Shape, MakeNamedMedium, MediumInterface, Include, GltfAsset
};

Dir LookupDirective(std::string_view w) {
    static const std::pair<const char *, Dir> table[] = {
        {"Camera", Dir::Camera}, {"Film", Dir::Film}, {"Sampler", Dir::Sampler},
        {"PixelFilter", Dir::PixelFilter}, {"Integrator", Dir::Integrator}, {"Accelerator", Dir::Accelerator},
        {"LookAt", Dir::LookAt}, {"Translate", Dir::Translate}, {"Rotate", Dir::Rotate}, {"Scale", Dir::Scale},
        {"Transform", Dir::Transform}, {"ConcatTransform", Dir::ConcatTransform},
        {"CoordinateSystem", Dir::CoordinateSystem}, {"CoordSysTransform", Dir::CoordSysTransform},
        {"ActiveTransform", Dir::ActiveTransform}, {"TransformTimes", Dir::TransformTimes},
        {"Identity", Dir::Identity}, {"ReverseOrientation", Dir::ReverseOrientation},
        {"WorldBegin", Dir::WorldBegin}, {"WorldEnd", Dir::WorldEnd}, {"AttributeBegin", Dir::AttributeBegin},
        {"AttributeEnd", Dir::AttributeEnd}, {"TransformBegin", Dir::TransformBegin},
        {"TransformEnd", Dir::TransformEnd}, {"ObjectBegin", Dir::ObjectBegin}, {"ObjectEnd", Dir::ObjectEnd},
        {"ObjectInstance", Dir::ObjectInstance}, {"Material", Dir::Material},
        {"MakeNamedMaterial", Dir::MakeNamedMaterial}, {"NamedMaterial", Dir::NamedMaterial},
        {"Texture", Dir::Texture}, {"LightSource", Dir::LightSource}, {"AreaLightSource", Dir::AreaLightSource},
        {"Shape", Dir::Shape}, {"MakeNamedMedium", Dir::MakeNamedMedium},
        {"MediumInterface", Dir::MediumInterface}, {"Include", Dir::Include},
        {"GltfAsset", Dir::GltfAsset},
    };
    for (const auto &e : table)
        if (w == e.first) return e.second;
    return Dir::Unknown;
}

// Cheap pre-check: every directive starts with an upper-case letter, numbers never do.
bool IsDirective(std::string_view w) {
    return !w.empty() && w[0] >= 'A' && w[0] <= 'Z' && LookupDirective(w) != Dir::Unknown;
}

enum class ValueKind { Numbers, Integers, Strings, Bools, Spectrum };

bool ParamTypeInfo(const std::string &t, ValueKind *kind, int *multiple) {
    static const struct { const char *name; ValueKind kind; int multiple; } types[] = {
        {"integer", ValueKind::Integers, 1}, {"float", ValueKind::Numbers, 1},
        {"point", ValueKind::Numbers, 3},    {"point2", ValueKind::Numbers, 2},
        {"point3", ValueKind::Numbers, 3},   {"vector", ValueKind::Numbers, 3},
        {"vector2", ValueKind::Numbers, 2},  {"vector3", ValueKind::Numbers, 3},
        {"normal", ValueKind::Numbers, 3},   {"normal3", ValueKind::Numbers, 3},
        {"rgb", ValueKind::Numbers, 3},      {"color", ValueKind::Numbers, 3},
        {"blackbody", ValueKind::Numbers, 2}, {"spectrum", ValueKind::Spectrum, 2},
        {"bool", ValueKind::Bools, 1},       {"string", ValueKind::Strings, 1},
        {"texture", ValueKind::Strings, 1},
    };
    for (const auto &e : types)
        if (t == e.name) {
            *kind = e.kind;
            *multiple = e.multiple;
            return true;
        }
    return false;
}

std::string Unescape(std::string_view s) {
    std::string r;
    r.reserve(s.size());
    for (size_t i = 0; i < s.size(); ++i) {
        if (s[i] != '\\' || i + 1 >= s.size()) {
            r.push_back(s[i]);
            continue;
        }
        char c = s[++i];
        switch (c) {
            case 'n': r.push_back('\n'); break;
            case 't': r.push_back('\t'); break;
            case 'r': r.push_back('\r'); break;
            case 'b': r.push_back('\b'); break;
            case 'f': r.push_back('\f'); break;
            default: r.push_back(c); break;  // \\ \" \' and anything else: the character itself
        }
    }
    return r;
}

bool ParseNumber(std::string_view w, double *v) {
    const char *b = w.data(), *e = w.data() + w.size();
    if (b != e && *b == '+') ++b;
    if (b == e) return false;
    auto r = std::from_chars(b, e, *v);
    return r.ec == std::errc() && r.ptr == e;
}

// ---------------------------------------------------------------- graphics state

struct GraphicsState {
    int material = -1;
    int areaLight = -1;
    bool reverseOrientation = false;
    std::string insideMedium, outsideMedium;
    // pbrt-v3 scopes named materials with AttributeBegin/End; shared until modified.
    std::shared_ptr<std::map<std::string, int>> namedMaterials = std::make_shared<std::map<std::string, int>>();
};

enum class BlockKind { Attribute, Transform, Object };

struct StackFrame {
    BlockKind kind;
    FileLoc loc;
    Transform ctm[2];
    int activeBits;
    GraphicsState gs;  // restored for Attribute/Object frames only
};

const char *BlockName(BlockKind k) {
    switch (k) {
        case BlockKind::Attribute: return "AttributeBegin";
        case BlockKind::Transform: return "TransformBegin";
        default: return "ObjectBegin";
    }
}

class Parser {
  public:
    explicit Parser(SceneDesc *scene) : scene_(scene) {}

    void parse(std::string text, const std::string &name, const std::string &dir) {
        pushFile(std::move(text), name, dir);
        run();
    }

  private:
    // ------------------------------------------------ locations & errors
    FileLoc locOf(const Token &t) const {
        FileLoc l;
        l.file = files_[t.file];
        l.line = t.line;
        l.column = t.column;
        return l;
    }
    [[noreturn]] void fail(const Token &t, const std::string &msg) const { throw Error(locOf(t), msg); }

    static std::string Show(const Token &t) {
        switch (t.kind) {
            case Tok::End: return "end of file";
            case Tok::String: return "string \"" + std::string(t.text) + "\"";
            default: return "'" + std::string(t.text) + "'";
        }
    }

    // ------------------------------------------------ token stream
    void pushFile(std::string text, const std::string &name, const std::string &dir) {
        files_.push_back(std::make_shared<const std::string>(name));
        lexers_.push_back(std::make_unique<Lexer>(std::move(text), int(files_.size()) - 1, dir));
        active_.push_back(lexers_.back().get());
    }

    Token lexNext() {
        auto failer = [this](const Token &t, const char *msg) { fail(t, msg); };
        for (;;) {
            Token t = active_.back()->next(failer);
            if (t.kind != Tok::End || active_.size() == 1) return t;
            active_.pop_back();  // end of an included file: continue in the includer
        }
    }
    Token next() {
        if (hasPeek_) {
            hasPeek_ = false;
            return peeked_;
        }
        return lexNext();
    }
    const Token &peek() {
        if (!hasPeek_) {
            peeked_ = lexNext();
            hasPeek_ = true;
        }
        return peeked_;
    }

    std::string stringValue(const Token &t) const { return t.escaped ? Unescape(t.text) : std::string(t.text); }

    std::string expectString(const char *directive, const char *what) {
        Token t = next();
        if (t.kind != Tok::String)
            fail(t, std::string(directive) + " expects a quoted " + what + ", got " + Show(t));
        return stringValue(t);
    }

    double expectNumber(const char *directive, int count) {
        Token t = next();
        double v;
        if (t.kind != Tok::Word || !ParseNumber(t.text, &v)) {
            if (t.kind == Tok::Word && !IsDirective(t.text))
                fail(t, "malformed number " + Show(t));
            fail(t, std::string(directive) + " expects " + std::to_string(count) + " numbers, got " + Show(t));
        }
        if (!std::isfinite(v)) fail(t, "non-finite number " + Show(t) + " (NaN and infinity are not valid values)");
        return v;
    }

    // n numbers, optionally enclosed in brackets.
    void expectNumbers(const char *directive, int n, double *out) {
        bool bracket = peek().kind == Tok::LBracket;
        Token open;
        if (bracket) open = next();
        for (int i = 0; i < n; ++i) out[i] = expectNumber(directive, n);
        if (bracket) {
            Token t = next();
            if (t.kind != Tok::RBracket)
                fail(t.kind == Tok::End ? open : t, std::string(directive) + " expects " + std::to_string(n) +
                                                        " numbers in '[ ]', got " + Show(t));
        }
    }

    // ------------------------------------------------ parameter lists
    ParamSet parseParams() {
        ParamSet ps;
        while (peek().kind == Tok::String) {
            Token decl = next();
            std::string d = stringValue(decl);
            Param p;
            p.loc = locOf(decl);
            {
                std::istringstream ss(d);
                std::string extra;
                if (!(ss >> p.type >> p.name) || (ss >> extra))
                    fail(decl, "malformed parameter declaration \"" + d + "\" (expected \"type name\")");
            }
            ValueKind kind;
            int multiple;
            if (!ParamTypeInfo(p.type, &kind, &multiple))
                fail(decl, "unknown parameter type '" + p.type + "' in \"" + d + "\"");

            if (peek().kind == Tok::LBracket) {
                Token open = next();
                for (;;) {
                    const Token &t = peek();
                    if (t.kind == Tok::RBracket) {
                        next();
                        break;
                    }
                    if (t.kind == Tok::End) fail(open, "unbalanced '[': no matching ']' before end of file");
                    if (t.kind == Tok::LBracket) fail(t, "unexpected '[' inside a parameter value list");
                    if (t.kind == Tok::Word && IsDirective(t.text))
                        fail(open, "unbalanced '[': no matching ']' before " + std::string(t.text));
                    addValue(p, kind, next());
                }
            } else {
                const Token &t = peek();
                if (t.kind == Tok::End || t.kind == Tok::RBracket ||
                    (t.kind == Tok::Word && IsDirective(t.text)))
                    fail(decl, "parameter \"" + d + "\" has no value");
                addValue(p, kind, next());
            }

            size_t count = p.numbers.size() + p.strings.size() + p.bools.size();
            if (count == 0) fail(decl, "parameter \"" + d + "\" has no values");
            if (kind == ValueKind::Spectrum && !p.strings.empty()) {
                if (!p.numbers.empty()) fail(decl, "parameter \"" + d + "\" mixes numbers and strings");
                if (p.strings.size() != 1)
                    fail(decl, "parameter \"" + d + "\" takes one spectrum name or file, got " +
                                   std::to_string(p.strings.size()));
                loadSpectrumFile(p, decl);
            } else if (count % multiple != 0) {
                std::string what = p.type == "rgb" || p.type == "color" ? "3 values per colour"
                                   : p.type == "blackbody"          ? "(temperature scale) pairs"
                                   : p.type == "spectrum"           ? "(wavelength value) pairs"
                                                                    : std::to_string(multiple) + " values per item";
                fail(decl, "parameter \"" + d + "\" needs " + what + ", got " + std::to_string(count) + " value" +
                               (count == 1 ? "" : "s"));
            }
            ps.add(std::move(p));
        }
        return ps;
    }

    void addValue(Param &p, ValueKind kind, const Token &t) {
        switch (kind) {
            case ValueKind::Numbers:
            case ValueKind::Integers:
            case ValueKind::Spectrum: {
                if (t.kind == Tok::String) {
                    if (kind == ValueKind::Spectrum) {
                        p.strings.push_back(stringValue(t));
                        return;
                    }
                    fail(t, "parameter \"" + p.type + " " + p.name + "\" expects numbers, got " + Show(t));
                }
                double v;
                if (!ParseNumber(t.text, &v)) fail(t, "malformed number " + Show(t));
                if (!std::isfinite(v))
                    fail(t, "non-finite number " + Show(t) + " in parameter \"" + p.type + " " + p.name +
                                "\" (NaN and infinity are not valid values)");
                if (kind == ValueKind::Integers && (v != std::floor(v) || std::abs(v) > 2147483647.0))
                    fail(t, "parameter \"integer " + p.name + "\" expects integers, got " + Show(t));
                p.numbers.push_back(v);
                return;
            }
            case ValueKind::Strings:
                if (t.kind != Tok::String)
                    fail(t, "parameter \"" + p.type + " " + p.name + "\" expects quoted strings, got " + Show(t));
                p.strings.push_back(stringValue(t));
                return;
            case ValueKind::Bools: {
                std::string s = t.kind == Tok::String ? stringValue(t) : std::string(t.text);
                if (s == "true") p.bools.push_back(true);
                else if (s == "false") p.bools.push_back(false);
                else fail(t, "parameter \"bool " + p.name + "\" expects true or false, got " + Show(t));
                return;
            }
        }
    }

    // "spectrum" given as a file: load its (lambda, value) pairs now, against
    // the scene directory as pbrt-v3 does. Names without '.' or '/' are named
    // spectra (e.g. "metal-Cu-eta"), left as strings for the lookup to reject.
    void loadSpectrumFile(Param &p, const Token &decl) {
        const std::string &f = p.strings[0];
        if (f.find('.') == std::string::npos && f.find('/') == std::string::npos) return;
        std::string path = scene_->resolve(f);
        try {
            p.numbers = ReadSpdFile(path);
        } catch (const Error &e) {
            fail(decl, std::string("spectrum file \"") + f + "\": " + e.what());
        }
        p.strings.clear();
    }

    // ------------------------------------------------ transforms
    template <typename F>
    void applyTransform(const Token &at, F &&make) {
        try {
            Transform t = make();
            for (int i = 0; i < 2; ++i)
                if (activeBits_ & (1 << i)) ctm_[i] = ctm_[i] * t;
        } catch (const Error &e) {
            if (dynamic_cast<const UnsupportedError *>(&e)) throw;
            std::string what = e.what(), prefix = std::string(at.text) + ": ";
            fail(at, what.rfind(prefix, 0) == 0 ? what : prefix + what);
        }
    }

    static Transform FromColumnMajor(const double *tr) {
        Matrix4 m(tr[0], tr[4], tr[8], tr[12], tr[1], tr[5], tr[9], tr[13], tr[2], tr[6], tr[10], tr[14], tr[3],
                  tr[7], tr[11], tr[15]);
        return Transform(m);
    }

    // ------------------------------------------------ block checks
    void requireOptions(const Token &t) {
        if (state_ == State::World)
            fail(t, std::string(t.text) + " is not allowed inside the world block (after WorldBegin)");
        if (state_ == State::Done) fail(t, std::string(t.text) + " after WorldEnd");
    }
    void requireWorld(const Token &t) {
        if (state_ == State::Options) fail(t, std::string(t.text) + " is not allowed before WorldBegin");
        if (state_ == State::Done) fail(t, std::string(t.text) + " after WorldEnd");
    }

    EntityDesc entity(const Token &t, std::string type, ParamSet ps) const {
        EntityDesc e;
        e.type = std::move(type);
        e.params = std::move(ps);
        e.loc = locOf(t);
        e.present = true;
        return e;
    }

    void setOption(EntityDesc &slot, const Token &t) {
        requireOptions(t);
        std::string type = expectString(std::string(t.text).c_str(), "type name");
        slot = entity(t, std::move(type), parseParams());
    }

    void pushFrame(BlockKind k, const Token &t) {
        stack_.push_back(StackFrame{k, locOf(t), {ctm_[0], ctm_[1]}, activeBits_, gs_});
    }
    void popFrame(BlockKind k, const Token &t) {
        if (stack_.empty()) fail(t, std::string(t.text) + " without matching " + BlockName(k));
        const StackFrame &f = stack_.back();
        if (f.kind != k)
            fail(t, std::string(t.text) + " does not match " + BlockName(f.kind) + " at " + f.loc.str());
        ctm_[0] = f.ctm[0];
        ctm_[1] = f.ctm[1];
        activeBits_ = f.activeBits;
        if (k != BlockKind::Transform) gs_ = f.gs;
        stack_.pop_back();
    }

    // ------------------------------------------------ main loop
    void run() {
        for (;;) {
            Token t = next();
            if (t.kind == Tok::End) {
                if (state_ != State::Done)
                    fail(t, state_ == State::Options ? "end of file before WorldBegin (missing WorldBegin/WorldEnd)"
                                                     : "missing WorldEnd at end of file");
                break;
            }
            if (t.kind == Tok::RBracket) fail(t, "unbalanced ']'");
            if (t.kind != Tok::Word) fail(t, "unexpected " + Show(t) + " (expected a directive)");
            Dir d = LookupDirective(t.text);
            if (d == Dir::Unknown) {
                double v;
                if (ParseNumber(t.text, &v)) fail(t, "unexpected number " + Show(t) + " (expected a directive)");
                fail(t, "unknown directive " + Show(t));
            }
            directive(d, t);
        }
        checkMedia();
    }

    void directive(Dir d, const Token &t) {
        const std::string name(t.text);
        const char *dn = name.c_str();
        if (state_ == State::Done) fail(t, name + " after WorldEnd");
        switch (d) {
            case Dir::Camera: {
                requireOptions(t);
                std::string type = expectString(dn, "type name");
                CameraDesc &c = scene_->camera;
                static_cast<EntityDesc &>(c) = entity(t, std::move(type), parseParams());
                noteMotion(t);
                c.cameraFromWorld = ctm_[0];
                c.mediumName = gs_.outsideMedium;
                namedCoordSys_["camera"] = {ctm_[0].inverse(), ctm_[1].inverse()};
                break;
            }
            case Dir::Film: setOption(scene_->film, t); break;
            case Dir::Sampler: setOption(scene_->sampler, t); break;
            case Dir::PixelFilter: setOption(scene_->filter, t); break;
            case Dir::Integrator: setOption(scene_->integrator, t); break;
            case Dir::Accelerator: setOption(scene_->accelerator, t); break;

            case Dir::LookAt: {
                double v[9];
                expectNumbers(dn, 9, v);
                applyTransform(t, [&] {
                    return gradus::LookAt(Point3(v[0], v[1], v[2]), Point3(v[3], v[4], v[5]), Vec3(v[6], v[7], v[8]));
                });
                break;
            }
            case Dir::Translate: {
                double v[3];
                expectNumbers(dn, 3, v);
                applyTransform(t, [&] { return gradus::Translate(Vec3(v[0], v[1], v[2])); });
                break;
            }
            case Dir::Rotate: {
                double v[4];
                expectNumbers(dn, 4, v);
                applyTransform(t, [&] { return gradus::Rotate(v[0], Vec3(v[1], v[2], v[3])); });
                break;
            }
            case Dir::Scale: {
                double v[3];
                expectNumbers(dn, 3, v);
                applyTransform(t, [&] { return gradus::Scale(v[0], v[1], v[2]); });
                break;
            }
            case Dir::Transform: {
                double v[16];
                expectNumbers(dn, 16, v);
                Transform saved[2] = {ctm_[0], ctm_[1]};
                for (int i = 0; i < 2; ++i)
                    if (activeBits_ & (1 << i)) ctm_[i] = Transform();
                try {
                    applyTransform(t, [&] { return FromColumnMajor(v); });
                } catch (...) {
                    ctm_[0] = saved[0];
                    ctm_[1] = saved[1];
                    throw;
                }
                break;
            }
            case Dir::ConcatTransform: {
                double v[16];
                expectNumbers(dn, 16, v);
                applyTransform(t, [&] { return FromColumnMajor(v); });
                break;
            }
            case Dir::Identity:
                for (int i = 0; i < 2; ++i)
                    if (activeBits_ & (1 << i)) ctm_[i] = Transform();
                break;
            case Dir::CoordinateSystem: {
                std::string n = expectString(dn, "name");
                namedCoordSys_[n] = {ctm_[0], ctm_[1]};
                break;
            }
            case Dir::CoordSysTransform: {
                Token nt = peek();
                std::string n = expectString(dn, "name");
                auto it = namedCoordSys_.find(n);
                if (it == namedCoordSys_.end()) fail(nt, "unknown coordinate system \"" + n + "\"");
                ctm_[0] = it->second[0];
                ctm_[1] = it->second[1];
                break;
            }
            case Dir::ActiveTransform: {
                Token a = next();
                if (a.kind == Tok::Word && a.text == "StartTime") activeBits_ = 1;
                else if (a.kind == Tok::Word && a.text == "EndTime") activeBits_ = 2;
                else if (a.kind == Tok::Word && a.text == "All") activeBits_ = 3;
                else fail(a, "ActiveTransform expects StartTime, EndTime or All, got " + Show(a));
                break;
            }
            case Dir::TransformTimes: {
                requireOptions(t);
                double v[2];
                expectNumbers(dn, 2, v);
                scene_->transformStartTime = v[0];
                scene_->transformEndTime = v[1];
                break;
            }
            case Dir::ReverseOrientation:
                requireWorld(t);
                gs_.reverseOrientation = !gs_.reverseOrientation;
                break;

            case Dir::WorldBegin:
                requireOptions(t);
                state_ = State::World;
                ctm_[0] = ctm_[1] = Transform();
                activeBits_ = 3;
                namedCoordSys_["world"] = {ctm_[0], ctm_[1]};
                break;
            case Dir::WorldEnd:
                requireWorld(t);
                if (!stack_.empty())
                    fail(t, "WorldEnd inside the " + std::string(BlockName(stack_.back().kind)) + " block opened at " +
                                stack_.back().loc.str());
                // pbrt-v3 builds the camera at WorldEnd with the media of the graphics
                // state then (a MediumInterface after Camera, even inside the world
                // block at top level, places the camera in that medium).
                scene_->camera.mediumName = gs_.outsideMedium;
                state_ = State::Done;
                break;

            case Dir::AttributeBegin:
                requireWorld(t);
                pushFrame(BlockKind::Attribute, t);
                break;
            case Dir::AttributeEnd:
                requireWorld(t);
                popFrame(BlockKind::Attribute, t);
                break;
            case Dir::TransformBegin:
                requireWorld(t);
                pushFrame(BlockKind::Transform, t);
                break;
            case Dir::TransformEnd:
                requireWorld(t);
                popFrame(BlockKind::Transform, t);
                break;

            case Dir::ObjectBegin: {
                requireWorld(t);
                Token nt = peek();
                std::string n = expectString(dn, "object name");
                if (!currentInstance_.empty())
                    fail(t, "ObjectBegin \"" + n + "\" inside the definition of object \"" + currentInstance_ + "\"");
                if (scene_->instances.count(n)) fail(nt, "object \"" + n + "\" is already defined");
                pushFrame(BlockKind::Object, t);
                currentInstance_ = n;
                InstanceDesc &inst = scene_->instances[n];
                inst.name = n;
                inst.loc = locOf(t);
                break;
            }
            case Dir::ObjectEnd:
                requireWorld(t);
                if (currentInstance_.empty()) fail(t, "ObjectEnd outside an object definition");
                popFrame(BlockKind::Object, t);
                currentInstance_.clear();
                break;
            case Dir::ObjectInstance: {
                requireWorld(t);
                Token nt = peek();
                std::string n = expectString(dn, "object name");
                if (!currentInstance_.empty())
                    fail(t, "ObjectInstance inside the definition of object \"" + currentInstance_ + "\"");
                if (!scene_->instances.count(n)) fail(nt, "ObjectInstance of unknown object \"" + n + "\"");
                noteMotion(t);
                scene_->instanceUses.push_back(InstanceUseDesc{n, ctm_[0], locOf(t)});
                break;
            }

            case Dir::Material: {
                requireWorld(t);
                std::string type = expectString(dn, "material type");
                MaterialDesc m;
                static_cast<EntityDesc &>(m) = entity(t, std::move(type), parseParams());
                scene_->materials.push_back(std::move(m));
                gs_.material = int(scene_->materials.size()) - 1;
                break;
            }
            case Dir::MakeNamedMaterial: {
                requireWorld(t);
                std::string n = expectString(dn, "material name");
                ParamSet ps = parseParams();
                const Param *tp = ps.find("type");  // marks it used
                if (!tp) fail(t, "MakeNamedMaterial \"" + n + "\" has no \"string type\" parameter");
                std::string type = ps.getString("type", "");
                MaterialDesc m;
                static_cast<EntityDesc &>(m) = entity(t, type, std::move(ps));
                m.name = n;
                scene_->materials.push_back(std::move(m));
                int idx = int(scene_->materials.size()) - 1;
                if (gs_.namedMaterials.use_count() > 1)
                    gs_.namedMaterials = std::make_shared<std::map<std::string, int>>(*gs_.namedMaterials);
                (*gs_.namedMaterials)[n] = idx;
                scene_->namedMaterials[n] = idx;
                break;
            }
            case Dir::NamedMaterial: {
                requireWorld(t);
                Token nt = peek();
                std::string n = expectString(dn, "material name");
                auto it = gs_.namedMaterials->find(n);
                if (it == gs_.namedMaterials->end()) fail(nt, "NamedMaterial: unknown material \"" + n + "\"");
                gs_.material = it->second;
                break;
            }
            case Dir::Texture: {
                requireWorld(t);
                TextureDesc tex;
                tex.name = expectString(dn, "texture name");
                Token vt = peek();
                tex.valueType = expectString(dn, "texture value type");
                if (tex.valueType == "color") tex.valueType = "spectrum";
                if (tex.valueType != "float" && tex.valueType != "spectrum")
                    fail(vt, "texture value type must be \"float\", \"spectrum\" or \"color\", got \"" +
                                 tex.valueType + "\"");
                std::string cls = expectString(dn, "texture class");
                static_cast<EntityDesc &>(tex) = entity(t, std::move(cls), parseParams());
                noteMotion(t);
                tex.worldFromTexture = ctm_[0];
                scene_->textures.push_back(std::move(tex));
                break;
            }
            case Dir::LightSource: {
                requireWorld(t);
                std::string type = expectString(dn, "light type");
                LightDesc l;
                static_cast<EntityDesc &>(l) = entity(t, std::move(type), parseParams());
                noteMotion(t);
                l.worldFromLight = ctm_[0];
                l.outsideMedium = gs_.outsideMedium;
                mediaRefs_.push_back({l.outsideMedium, l.loc});
                scene_->lights.push_back(std::move(l));
                break;
            }
            case Dir::AreaLightSource: {
                requireWorld(t);
                std::string type = expectString(dn, "area light type");
                scene_->areaLights.push_back(entity(t, std::move(type), parseParams()));
                gs_.areaLight = int(scene_->areaLights.size()) - 1;
                break;
            }
            case Dir::Shape: {
                requireWorld(t);
                std::string type = expectString(dn, "shape type");
                ShapeDesc s;
                static_cast<EntityDesc &>(s) = entity(t, std::move(type), parseParams());
                noteMotion(t);
                s.worldFromObject = ctm_[0];
                s.reverseOrientation = gs_.reverseOrientation;
                s.material = gs_.material;
                s.areaLight = gs_.areaLight;
                s.insideMedium = gs_.insideMedium;
                s.outsideMedium = gs_.outsideMedium;
                mediaRefs_.push_back({s.insideMedium, s.loc});
                mediaRefs_.push_back({s.outsideMedium, s.loc});
                if (!currentInstance_.empty()) scene_->instances[currentInstance_].shapes.push_back(std::move(s));
                else scene_->shapes.push_back(std::move(s));
                break;
            }
            case Dir::MakeNamedMedium: {
                if (state_ == State::Done) fail(t, name + " after WorldEnd");
                MediumDesc m;
                m.name = expectString(dn, "medium name");
                ParamSet ps = parseParams();
                if (!ps.find("type")) fail(t, "MakeNamedMedium \"" + m.name + "\" has no \"string type\" parameter");
                std::string type = ps.getString("type", "");
                static_cast<EntityDesc &>(m) = entity(t, type, std::move(ps));
                noteMotion(t);
                m.worldFromMedium = ctm_[0];
                scene_->media.push_back(std::move(m));
                break;
            }
            case Dir::MediumInterface: {
                std::string inside = expectString(dn, "medium name");
                std::string outside = inside;
                if (peek().kind == Tok::String) outside = stringValue(next());
                gs_.insideMedium = inside;
                gs_.outsideMedium = outside;
                break;
            }
            case Dir::Include: {
                Token ft = peek();
                std::string f = expectString(dn, "file name");
                std::string path = JoinPath(active_.back()->dir(), f);
                if (active_.size() > 64) fail(t, "Include nested too deeply (recursive Include of \"" + f + "\"?)");
                std::string text;
                if (!ReadWholeFile(path, &text))
                    fail(ft, "cannot open included file \"" + f + "\" (looked for " + path + ")");
                // The peeked token (if any) belongs after the Include: none is
                // pending here because expectString consumed the only lookahead.
                pushFile(std::move(text), path, DirectoryOf(path));
                break;
            }
            case Dir::GltfAsset: {
                // Gradus extension: GltfAsset "file.gltf|glb" ["string camera" "NAME"]
                // places a glTF asset's meshes, materials and lights under the CTM;
                // with "camera", that camera of the asset replaces the scene's Camera.
                requireWorld(t);
                if (!currentInstance_.empty()) fail(t, "GltfAsset inside ObjectBegin");
                Token ft = peek();
                std::string f = expectString(dn, "glTF file name");
                ParamSet ps = parseParams();
                GltfOptions go;
                go.camera = ps.getString("camera", "");
                ps.checkUnused("GltfAsset");
                noteMotion(t);
                AddGltfAsset(JoinPath(active_.back()->dir(), f), ctm_[0], go, !go.camera.empty(), locOf(ft), scene_);
                break;
            }
            case Dir::Unknown: break;
        }
    }

    // An entity placed while the start and end transforms differ would need
    // motion blur: remember the first one (the scene builder refuses it).
    void noteMotion(const Token &t) {
        if (!(ctm_[0] == ctm_[1]) && !scene_->motionBlur) {
            scene_->motionBlur = true;
            scene_->motionLoc = locOf(t);
        }
    }

    void checkMedia() {
        std::set<std::string> known;
        for (const auto &m : scene_->media) known.insert(m.name);
        if (!scene_->camera.mediumName.empty() && !known.count(scene_->camera.mediumName))
            throw Error(scene_->camera.loc, "Camera: unknown medium \"" + scene_->camera.mediumName + "\"");
        for (const auto &r : mediaRefs_)
            if (!r.first.empty() && !known.count(r.first))
                throw Error(r.second, "unknown medium \"" + r.first + "\" (no MakeNamedMedium of that name)");
    }

    enum class State { Options, World, Done };

    SceneDesc *scene_;
    std::vector<std::shared_ptr<const std::string>> files_;
    std::vector<std::unique_ptr<Lexer>> lexers_;  // kept alive: tokens view their text
    std::vector<Lexer *> active_;                  // include stack
    Token peeked_;
    bool hasPeek_ = false;

    State state_ = State::Options;
    Transform ctm_[2];
    int activeBits_ = 3;
    GraphicsState gs_;
    std::vector<StackFrame> stack_;
    std::map<std::string, std::array<Transform, 2>> namedCoordSys_;
    std::string currentInstance_;
    std::vector<std::pair<std::string, FileLoc>> mediaRefs_;
};

}  // namespace

std::string SceneDesc::resolve(const std::string &filename) const {
    if (filename.empty() || IsAbsolute(filename)) return filename;
    return JoinPath(sceneDirectory.empty() ? "." : sceneDirectory, filename);
}

SceneDesc ParseFile(const std::string &filename) {
    std::string text;
    if (!ReadWholeFile(filename, &text)) throw Error(filename + ": cannot open scene file");
    SceneDesc scene;
    scene.sceneDirectory = DirectoryOf(filename);
    Parser(&scene).parse(std::move(text), filename, scene.sceneDirectory);
    return scene;
}

SceneDesc ParseString(const std::string &text, const std::string &name, const std::string &directory) {
    SceneDesc scene;
    scene.sceneDirectory = directory;
    Parser(&scene).parse(text, name, directory);
    return scene;
}

}  // namespace gradus
