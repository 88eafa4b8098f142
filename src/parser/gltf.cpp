// glTF 2.0 loader (tinygltf for JSON, buffers and image decoding; everything
// it returns is validated here before use). References: the glTF 2.0
// specification (accessors 3.6, node hierarchy 3.5, cameras 3.10, materials
// 3.9, samplers 3.8) and the extensions KHR_lights_punctual,
// KHR_materials_emissive_strength, KHR_materials_ior,
// KHR_materials_transmission, KHR_texture_transform, KHR_mesh_quantization.
#include "parser/gltf.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include <sys/stat.h>

#include <tiny_gltf.h>

#include "core/error.h"
#include "core/provenance.h"

namespace gradus {
namespace {

namespace tg = tinygltf;

const std::set<std::string> kSupportedExtensions = {
    "KHR_lights_punctual",      "KHR_materials_emissive_strength", "KHR_materials_ior",
    "KHR_materials_transmission", "KHR_texture_transform",         "KHR_mesh_quantization"};

// ---------------------------------------------------------------- JSON positions
// Finds the line and column of the value at a JSON pointer ("/meshes/0/...")
// in JSON text that tinygltf has already accepted; the deepest existing prefix
// when the pointer names something absent.
class JsonLocator {
  public:
    explicit JsonLocator(const std::string &text) : s_(text) {}
    std::pair<int, int> locate(const std::string &pointer) const {
        std::vector<std::string> path;
        std::stringstream ss(pointer);
        std::string part;
        while (std::getline(ss, part, '/'))
            if (!part.empty()) path.push_back(part);
        size_t best = skipWs(0);
        size_t i = best;
        find(&i, path, 0, &best, 0);
        return lineCol(best);
    }

  private:
    size_t skipWs(size_t i) const {
        while (i < s_.size() && std::isspace((unsigned char)s_[i])) ++i;
        return i;
    }
    // Reads a string starting at s_[*i] == '"'; returns its raw contents.
    std::string readString(size_t *i) const {
        std::string out;
        ++*i;
        while (*i < s_.size() && s_[*i] != '"') {
            if (s_[*i] == '\\' && *i + 1 < s_.size()) ++*i;
            out += s_[(*i)++];
        }
        ++*i;
        return out;
    }
    // Parses the value at *i; records *best when the path matches to depth k.
    void find(size_t *i, const std::vector<std::string> &path, size_t k, size_t *best, int depth) const {
        *i = skipWs(*i);
        if (*i >= s_.size() || depth > 512) return;
        bool onPath = k <= path.size();
        if (onPath) *best = *i;
        char c = s_[*i];
        if (c == '{') {
            ++*i;
            for (;;) {
                *i = skipWs(*i);
                if (*i >= s_.size()) return;
                if (s_[*i] == '}') { ++*i; return; }
                if (s_[*i] == ',') { ++*i; continue; }
                if (s_[*i] != '"') return;
                std::string key = readString(i);
                *i = skipWs(*i);
                if (*i < s_.size() && s_[*i] == ':') ++*i;
                bool match = onPath && k < path.size() && key == path[k];
                find(i, path, match ? k + 1 : path.size() + 1, best, depth + 1);
            }
        } else if (c == '[') {
            ++*i;
            size_t index = 0;
            for (;;) {
                *i = skipWs(*i);
                if (*i >= s_.size()) return;
                if (s_[*i] == ']') { ++*i; return; }
                if (s_[*i] == ',') { ++*i; ++index; continue; }
                bool match = onPath && k < path.size() && path[k] == std::to_string(index);
                find(i, path, match ? k + 1 : path.size() + 1, best, depth + 1);
            }
        } else if (c == '"') {
            readString(i);
        } else {
            while (*i < s_.size() && !std::strchr(",]} \t\r\n", s_[*i])) ++*i;
        }
    }
    std::pair<int, int> lineCol(size_t off) const {
        int line = 1, col = 1;
        for (size_t j = 0; j < off && j < s_.size(); ++j) {
            if (s_[j] == '\n') ++line, col = 1;
            else ++col;
        }
        return {line, col};
    }
    const std::string &s_;
};

// ---------------------------------------------------------------- file access
std::vector<unsigned char> ReadBytes(const std::string &path, std::string *err) {
    std::vector<unsigned char> data;
    switch (ReadFileBytes(path, &data)) {
    case FileRead::CannotOpen: *err = "cannot open \"" + path + "\": " + std::strerror(errno); break;
    case FileRead::ReadError: *err = "cannot read \"" + path + "\""; break;
    case FileRead::Ok: break;
    }
    return data;
}

bool FsFileExists(const std::string &path, void *) { return std::ifstream(path).good(); }
std::string FsExpand(const std::string &path, void *) { return path; }  // no ~ or $VAR expansion
bool FsRead(std::vector<unsigned char> *out, std::string *err, const std::string &path, void *) {
    // Buffers and images are regular files (a device such as /dev/zero would be read forever).
    struct stat st;
    if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {
        if (err) *err += "\"" + path + "\" is not a regular file";
        return false;
    }
    std::string e;
    *out = ReadBytes(path, &e);
    if (!e.empty()) {
        if (err) *err += e;
        return false;
    }
    RecordInputFile(path, out->data(), out->size());
    return true;
}
bool FsWrite(std::string *err, const std::string &, const std::vector<unsigned char> &, void *) {
    if (err) *err += "writing is not supported";
    return false;
}

std::string Lower(std::string s) {
    for (char &c : s) c = char(std::tolower((unsigned char)c));
    return s;
}

std::string DirectoryOf(const std::string &path) {
    size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? "." : path.substr(0, slash);
}

std::string StemOf(const std::string &path) {
    size_t slash = path.find_last_of('/');
    std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
    size_t dot = base.find_last_of('.');
    return dot == std::string::npos ? base : base.substr(0, dot);
}

// ---------------------------------------------------------------- the loader
class Loader {
  public:
    Loader(const std::string &filename, const GltfOptions &opts, SceneDesc *desc)
        : filename_(filename), opts_(opts), desc_(desc), file_(std::make_shared<const std::string>(filename)) {}

    void load(const FileLoc &fileLoc) {
        std::string err;
        std::vector<unsigned char> bytes = ReadBytes(filename_, &err);
        if (!err.empty()) throw Error(fileLoc, err);
        RecordInputFile(filename_, bytes.data(), bytes.size());
        bool binary = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
        if (binary) {
            jsonLabel_ = std::make_shared<const std::string>(filename_ + " (JSON chunk)");
            // GLB header (12 bytes) and the JSON chunk header (8 bytes), checked
            // here so that a truncated file gets a precise message.
            auto u32 = [&](size_t off) {
                uint32_t v = 0;
                std::memcpy(&v, bytes.data() + off, 4);
                return v;
            };
            if (bytes.size() < 20) throw Error(at0(), "truncated .glb: " + std::to_string(bytes.size()) + " bytes, the headers need 20");
            if (u32(4) != 2) throw Error(at0(), ".glb version " + std::to_string(u32(4)) + " (only glTF 2.0 is read)");
            if (u32(8) != bytes.size())
                throw Error(at0(), ".glb header says " + std::to_string(u32(8)) + " bytes, the file has " +
                                       std::to_string(bytes.size()) + " (truncated or padded)");
            uint32_t jsonLen = u32(12);
            if (u32(16) != 0x4E4F534Au) throw Error(at0(), ".glb: the first chunk is not JSON");
            if (jsonLen > bytes.size() - 20) throw Error(at0(), ".glb: the JSON chunk runs past the end of the file");
            json_.assign(reinterpret_cast<const char *>(bytes.data()) + 20, jsonLen);
            // tinygltf 2.8 bounds the BIN chunk's length without its 8-byte header
            // and then reads up to 8 bytes past the end of the file: check it here.
            const size_t binAt = 20 + size_t(jsonLen);
            if (binAt < bytes.size()) {
                if (bytes.size() - binAt < 8) throw Error(at0(), ".glb: truncated chunk header after the JSON chunk");
                if (u32(binAt) > bytes.size() - binAt - 8)
                    throw Error(at0(), ".glb: the BIN chunk (" + std::to_string(u32(binAt)) +
                                           " bytes) runs past the end of the file");
            }
        } else {
            json_.assign(bytes.begin(), bytes.end());
        }
        tg::TinyGLTF loader;
        tg::FsCallbacks fs{&FsFileExists, &FsExpand, &FsRead, &FsWrite, nullptr};
        loader.SetFsCallbacks(fs);
        loader.SetPreserveImageChannels(true);
        std::string warn;
        err.clear();
        bool ok;
        const std::string base = DirectoryOf(filename_);
        try {
            if (binary)
                ok = loader.LoadBinaryFromMemory(&model_, &err, &warn, bytes.data(), unsigned(bytes.size()), base);
            else
                ok = loader.LoadASCIIFromString(&model_, &err, &warn, json_.data(), unsigned(json_.size()), base);
        } catch (const std::exception &e) {
            ok = false;
            err = e.what();
        }
        if (!ok) {
            const std::string msg = Trim(err.empty() ? warn : err);
            throw Error(locateLoaderMessage(msg), "not a valid glTF 2.0 file: " + msg);
        }
        checkExtensions();
    }

    void addContent(const Transform &worldFromAsset, bool useCamera, bool wholeScene) {
        firstShape_ = desc_->shapes.size();
        loadImages();
        loadMaterials();
        traverse(worldFromAsset);
        placeMeshes();
        if (useCamera) chooseCamera(wholeScene);
    }

    bool hasPunctualLights() const { return punctual_; }
    bool hasEmitters() const { return emissive_; }
    Float cameraAspect() const { return cameraAspect_; }

  private:
    // ---- errors
    FileLoc at0() const {
        FileLoc l;
        l.file = jsonLabel_ ? jsonLabel_ : file_;
        return l;
    }
    FileLoc at(const std::string &pointer) const {
        FileLoc l = at0();
        if (!json_.empty()) {
            auto lc = JsonLocator(json_).locate(pointer);
            l.line = lc.first, l.column = lc.second;
        }
        return l;
    }
    // tinygltf's messages: JSON syntax errors carry "line L, column C"
    // (nlohmann); missing buffers and images name "buffer[i]" / "image[i]".
    FileLoc locateLoaderMessage(const std::string &msg) const {
        FileLoc l = at0();
        int line = 0, col = 0;
        size_t p = msg.find("line ");
        if (p != std::string::npos && std::sscanf(msg.c_str() + p, "line %d, column %d", &line, &col) == 2 && line > 0) {
            l.line = line, l.column = std::max(1, col);
            return l;
        }
        for (const char *kind : {"buffer", "image"}) {
            size_t q = msg.find(std::string(kind) + "[");
            int idx = -1;
            if (q != std::string::npos && std::sscanf(msg.c_str() + q + std::strlen(kind), "[%d]", &idx) == 1 && idx >= 0 &&
                !json_.empty())
                return at("/" + std::string(kind) + "s/" + std::to_string(idx) + "/uri");
        }
        return l;
    }
    [[noreturn]] void fail(const std::string &pointer, const std::string &msg) const {
        throw Error(at(pointer), msg + " (at " + pointer + ")");
    }
    static std::string Trim(std::string s) {
        while (!s.empty() && std::isspace((unsigned char)s.back())) s.pop_back();
        return s;
    }
    void note(const std::string &msg) { desc_->notes.push_back(filename_ + ": " + msg); }

    void checkExtensions() {
        for (size_t i = 0; i < model_.extensionsRequired.size(); ++i) {
            const std::string &e = model_.extensionsRequired[i];
            if (!kSupportedExtensions.count(e))
                fail("/extensionsRequired/" + std::to_string(i),
                     "required extension \"" + e + "\" is not supported (supported: KHR_lights_punctual, "
                     "KHR_materials_emissive_strength, KHR_materials_ior, KHR_materials_transmission, "
                     "KHR_texture_transform, KHR_mesh_quantization)");
        }
        std::string ignored;
        for (const auto &e : model_.extensionsUsed)
            if (!kSupportedExtensions.count(e)) ignored += (ignored.empty() ? "" : ", ") + e;
        if (!ignored.empty()) note("optional extensions not supported, ignored: " + ignored);
    }

    // ---- accessors
    static int ComponentSize(int type) {
        switch (type) {
            case TINYGLTF_COMPONENT_TYPE_BYTE:
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
            case TINYGLTF_COMPONENT_TYPE_SHORT:
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
            case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
            default: return 0;  // INT and DOUBLE are not glTF 2.0 accessor types
        }
    }
    static int NumComponents(int type) {
        switch (type) {
            case TINYGLTF_TYPE_SCALAR: return 1;
            case TINYGLTF_TYPE_VEC2: return 2;
            case TINYGLTF_TYPE_VEC3: return 3;
            case TINYGLTF_TYPE_VEC4: return 4;
            case TINYGLTF_TYPE_MAT2: return 4;
            case TINYGLTF_TYPE_MAT3: return 9;
            case TINYGLTF_TYPE_MAT4: return 16;
            default: return 0;
        }
    }
    static double Decode(const unsigned char *p, int type, bool normalized) {
        switch (type) {
            case TINYGLTF_COMPONENT_TYPE_FLOAT: {
                float f;
                std::memcpy(&f, p, 4);
                return f;
            }
            case TINYGLTF_COMPONENT_TYPE_BYTE: {
                int8_t v;
                std::memcpy(&v, p, 1);
                return normalized ? std::max(v / 127.0, -1.0) : v;
            }
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : p[0];
            case TINYGLTF_COMPONENT_TYPE_SHORT: {
                int16_t v;
                std::memcpy(&v, p, 2);
                return normalized ? std::max(v / 32767.0, -1.0) : v;
            }
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                uint16_t v;
                std::memcpy(&v, p, 2);
                return normalized ? v / 65535.0 : v;
            }
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
                uint32_t v;
                std::memcpy(&v, p, 4);
                return normalized ? v / 4294967295.0 : v;
            }
        }
        return 0;
    }
    // Bytes [offset, offset + stride (count - 1) + elem) of buffer view `bv`, checked.
    const unsigned char *viewData(int bv, size_t offset, size_t stride, size_t count, size_t elem,
                                  const std::string &ptr) const {
        if (bv < 0 || bv >= int(model_.bufferViews.size()))
            fail(ptr, "buffer view " + std::to_string(bv) + " does not exist (" +
                          std::to_string(model_.bufferViews.size()) + " buffer views)");
        const tg::BufferView &v = model_.bufferViews[bv];
        const std::string vptr = "/bufferViews/" + std::to_string(bv);
        if (v.buffer < 0 || v.buffer >= int(model_.buffers.size()))
            fail(vptr + "/buffer", "buffer " + std::to_string(v.buffer) + " does not exist");
        const tg::Buffer &b = model_.buffers[v.buffer];
        if (v.byteOffset > b.data.size() || v.byteLength > b.data.size() - v.byteOffset)
            fail(vptr, "buffer view [" + std::to_string(v.byteOffset) + ", +" + std::to_string(v.byteLength) +
                           ") lies outside buffer " + std::to_string(v.buffer) + " of " +
                           std::to_string(b.data.size()) + " bytes (missing or truncated buffer?)");
        // Overflow-free: count <= 2^31 and stride <= 2^16 are checked by the caller.
        uint64_t need = uint64_t(offset) + uint64_t(stride) * (count - 1) + elem;
        if (need > v.byteLength)
            fail(ptr, "accessor needs " + std::to_string(need) + " bytes of buffer view " + std::to_string(bv) +
                          ", which has " + std::to_string(v.byteLength));
        return b.data.data() + v.byteOffset;
    }

    struct AccessorData {
        size_t count = 0;
        int ncomp = 0;
        std::vector<double> v;  // count * ncomp
    };

    // Reads accessor `idx` of one of `types`; integer component types are
    // allowed unless floatOnly (KHR_mesh_quantization allows them for most
    // attributes). Non-finite values are errors.
    AccessorData readAccessor(int idx, std::initializer_list<int> types, const std::string &user) const {
        const std::string ptr = "/accessors/" + std::to_string(idx);
        if (idx < 0 || idx >= int(model_.accessors.size()))
            fail(user, "accessor " + std::to_string(idx) + " does not exist (" +
                           std::to_string(model_.accessors.size()) + " accessors)");
        const tg::Accessor &a = model_.accessors[idx];
        if (std::find(types.begin(), types.end(), a.type) == types.end())
            fail(ptr + "/type", "accessor has the wrong type for " + user);
        const int csize = ComponentSize(a.componentType);
        if (!csize) fail(ptr + "/componentType", "invalid componentType " + std::to_string(a.componentType));
        const int nc = NumComponents(a.type);
        // Accessors without a buffer view are zeros (plus sparse values): their
        // size is bounded here, as the others are by their buffers.
        if (a.bufferView < 0 && a.count > (size_t(1) << 24))
            fail(ptr + "/count", "accessor without bufferView has count " + std::to_string(a.count) +
                                     " (at most 2^24 zero-initialised elements are read)");
        if (a.count == 0 || a.count > (size_t(1) << 31))
            fail(ptr + "/count", "accessor count " + std::to_string(a.count) + " is out of range [1, 2^31]");
        AccessorData d;
        d.count = a.count;
        d.ncomp = nc;
        d.v.assign(a.count * nc, 0.0);  // no bufferView: zeros (then sparse values)
        const size_t elem = size_t(csize) * nc;
        if (a.bufferView >= 0) {
            if (a.bufferView >= int(model_.bufferViews.size()))
                fail(ptr + "/bufferView", "buffer view " + std::to_string(a.bufferView) + " does not exist");
            const tg::BufferView &bv = model_.bufferViews[a.bufferView];
            size_t stride = bv.byteStride ? bv.byteStride : elem;
            if (bv.byteStride && (bv.byteStride < elem || bv.byteStride > 252 || bv.byteStride % csize))
                fail("/bufferViews/" + std::to_string(a.bufferView) + "/byteStride",
                     "byteStride " + std::to_string(bv.byteStride) + " is invalid for this accessor");
            if (a.byteOffset % csize) fail(ptr + "/byteOffset", "byteOffset is not a multiple of the component size");
            const unsigned char *base = viewData(a.bufferView, a.byteOffset, stride, a.count, elem, ptr);
            for (size_t i = 0; i < a.count; ++i)
                for (int c = 0; c < nc; ++c)
                    d.v[i * nc + c] = Decode(base + a.byteOffset + i * stride + size_t(c) * csize, a.componentType,
                                             a.normalized);
        }
        if (a.sparse.isSparse) {
            const std::string sp = ptr + "/sparse";
            int n = a.sparse.count;
            if (n <= 0 || size_t(n) > a.count) fail(sp + "/count", "sparse count out of range");
            int it = a.sparse.indices.componentType;
            int isz = ComponentSize(it);
            if (!isz || it == TINYGLTF_COMPONENT_TYPE_FLOAT || it == TINYGLTF_COMPONENT_TYPE_BYTE ||
                it == TINYGLTF_COMPONENT_TYPE_SHORT)
                fail(sp + "/indices/componentType", "sparse indices must be unsigned integers");
            if (a.sparse.indices.byteOffset < 0 || a.sparse.values.byteOffset < 0)
                fail(sp, "negative sparse byteOffset");
            const unsigned char *ib = viewData(a.sparse.indices.bufferView, a.sparse.indices.byteOffset, isz, n, isz,
                                               sp + "/indices");
            const unsigned char *vb = viewData(a.sparse.values.bufferView, a.sparse.values.byteOffset, elem, n, elem,
                                               sp + "/values");
            for (int k = 0; k < n; ++k) {
                double target = Decode(ib + a.sparse.indices.byteOffset + size_t(k) * isz, it, false);
                if (target >= double(a.count)) fail(sp + "/indices", "sparse index " + std::to_string(size_t(target)) + " out of range");
                for (int c = 0; c < nc; ++c)
                    d.v[size_t(target) * nc + c] = Decode(vb + a.sparse.values.byteOffset + size_t(k) * elem +
                                                              size_t(c) * csize,
                                                          a.componentType, a.normalized);
            }
        }
        for (double x : d.v)
            if (!std::isfinite(x)) fail(ptr, "accessor holds a value that is not finite");
        return d;
    }

    // ---- images and textures
    void loadImages() {
        imageBase_ = int(desc_->images.size());
        for (size_t i = 0; i < model_.images.size(); ++i) {
            const tg::Image &im = model_.images[i];
            auto e = std::make_shared<EmbeddedImage>();
            e->name = im.name.empty() ? "image " + std::to_string(i) : im.name;
            const std::string ptr = "/images/" + std::to_string(i);
            if (im.width <= 0 || im.height <= 0 || im.component <= 0 || im.component > 4 ||
                (im.bits != 8 && im.bits != 16))
                fail(ptr, "image could not be decoded (only 8- and 16-bit PNG and JPEG are read)");
            size_t n = size_t(im.width) * im.height * im.component;
            if (im.image.size() != n * (im.bits / 8)) fail(ptr, "decoded image has the wrong size");
            e->width = im.width, e->height = im.height, e->channels = im.component;
            e->texels.resize(n);
            for (size_t k = 0; k < n; ++k) {
                if (im.bits == 8) e->texels[k] = uint16_t(im.image[k] * 257);
                else std::memcpy(&e->texels[k], &im.image[2 * k], 2);
            }
            desc_->images.push_back(e);
        }
    }

    // A texture reference of a material: a "gltfimage" TextureDesc named
    // after it. kind: "spectrum" (channel rgb) or "float" (channel r/g/b/a).
    // Returns the texture's name; *texCoord receives the uv set it uses.
    std::string makeTexture(const tg::TextureInfo &info, int texCoordIn, const std::string &ptr, const std::string &kind,
                            const std::string &channel, bool srgb, const std::array<double, 4> &factor,
                            Float cutoff, int *texCoord) {
        int ti = info.index;
        if (ti < 0 || ti >= int(model_.textures.size()))
            fail(ptr + "/index", "texture " + std::to_string(ti) + " does not exist");
        const tg::Texture &t = model_.textures[ti];
        if (t.source < 0 || t.source >= int(model_.images.size()))
            fail("/textures/" + std::to_string(ti) + "/source", "texture has no image (source " +
                                                                   std::to_string(t.source) + ")");
        TextureDesc td;
        td.type = "gltfimage";
        td.valueType = kind;
        td.loc = at(ptr);
        td.present = true;
        td.name = "gltf:" + filename_ + ptr + ":" + channel + (cutoff >= 0 ? ":cut" : "");
        addInt(td.params, "image", imageBase_ + t.source, td.loc);
        addString(td.params, "channel", channel, td.loc);
        addFloats(td.params, "factor", {factor[0], factor[1], factor[2], factor[3]}, td.loc);
        addBool(td.params, "srgb", srgb, td.loc);
        if (cutoff >= 0) addFloats(td.params, "cutoff", {cutoff}, td.loc);
        std::string wrapU = "repeat", wrapV = "repeat", filter = "linear";
        if (t.sampler >= 0) {
            if (t.sampler >= int(model_.samplers.size()))
                fail("/textures/" + std::to_string(ti) + "/sampler", "sampler " + std::to_string(t.sampler) + " does not exist");
            const tg::Sampler &s = model_.samplers[t.sampler];
            auto wrap = [&](int w, const char *which) -> std::string {
                if (w == TINYGLTF_TEXTURE_WRAP_REPEAT) return "repeat";
                if (w == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE) return "clamp";
                if (w == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT) return "mirror";
                fail("/samplers/" + std::to_string(t.sampler) + "/" + which, "invalid wrap mode " + std::to_string(w));
            };
            wrapU = wrap(s.wrapS, "wrapS"), wrapV = wrap(s.wrapT, "wrapT");
            if (s.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST) filter = "nearest";
        }
        addString(td.params, "wrapu", wrapU, td.loc);
        addString(td.params, "wrapv", wrapV, td.loc);
        addString(td.params, "filter", filter, td.loc);
        *texCoord = texCoordIn;
        auto ext = info.extensions.find("KHR_texture_transform");
        if (ext != info.extensions.end() && ext->second.IsObject()) {
            const tg::Value &v = ext->second;
            auto num2 = [&](const char *key, double d0, double d1) -> std::array<double, 2> {
                if (!v.Has(key)) return {d0, d1};
                const tg::Value &a = v.Get(key);
                if (!a.IsArray() || a.ArrayLen() != 2 || !a.Get(0).IsNumber() || !a.Get(1).IsNumber())
                    fail(ptr + "/extensions/KHR_texture_transform/" + key, "needs two numbers");
                return {a.Get(0).GetNumberAsDouble(), a.Get(1).GetNumberAsDouble()};
            };
            auto off = num2("offset", 0, 0), sc = num2("scale", 1, 1);
            double rot = 0;
            if (v.Has("rotation")) {
                if (!v.Get("rotation").IsNumber()) fail(ptr + "/extensions/KHR_texture_transform/rotation", "not a number");
                rot = v.Get("rotation").GetNumberAsDouble();
            }
            if (v.Has("texCoord") && v.Get("texCoord").IsNumber()) *texCoord = v.Get("texCoord").GetNumberAsInt();
            // KHR_texture_transform: uv' = T(offset) R(rotation) S(scale) uv, with
            // R = [cos -sin; sin cos] as its GLSL (column-major mat3) writes it.
            double c = std::cos(rot), s = std::sin(rot);
            addFloats(td.params, "uvtransform", {c * sc[0], -s * sc[1], off[0], s * sc[0], c * sc[1], off[1]}, td.loc);
        }
        if (*texCoord < 0) fail(ptr + "/texCoord", "texCoord " + std::to_string(*texCoord) + " is negative");
        desc_->textures.push_back(std::move(td));
        return desc_->textures.back().name;
    }

    static void addNumbers(ParamSet &ps, const char *type, const std::string &name, std::vector<double> v,
                           const FileLoc &loc) {
        Param p;
        p.type = type;
        p.name = name;
        p.loc = loc;
        p.numbers = std::move(v);
        ps.add(std::move(p));
    }
    static void addFloats(ParamSet &ps, const std::string &name, std::vector<double> v, const FileLoc &loc) {
        addNumbers(ps, "float", name, std::move(v), loc);
    }
    static void addInt(ParamSet &ps, const std::string &name, int v, const FileLoc &loc) {
        addNumbers(ps, "integer", name, {double(v)}, loc);
    }
    static void addStrings(ParamSet &ps, const char *type, const std::string &name, const std::string &v,
                           const FileLoc &loc) {
        Param p;
        p.type = type;
        p.name = name;
        p.loc = loc;
        p.strings = {v};
        ps.add(std::move(p));
    }
    static void addString(ParamSet &ps, const std::string &name, const std::string &v, const FileLoc &loc) {
        addStrings(ps, "string", name, v, loc);
    }
    static void addTextureRef(ParamSet &ps, const std::string &name, const std::string &tex, const FileLoc &loc) {
        addStrings(ps, "texture", name, tex, loc);
    }
    static void addBool(ParamSet &ps, const std::string &name, bool v, const FileLoc &loc) {
        Param p;
        p.type = "bool";
        p.name = name;
        p.loc = loc;
        p.bools = {v};
        ps.add(std::move(p));
    }

    // ---- materials
    struct MaterialInfo {
        int descIndex = -1;    // into SceneDesc::materials
        int texCoord = 0;      // uv set the material's textures read
        bool normalMap = false;
        Spectrum emission;     // emissiveFactor * emissiveStrength
        std::string emissionTexture;  // emissiveTexture (area light "Lmap")
        bool doubleSided = false;
        std::string alphaTexture;  // MASK with a base colour texture
        bool cutAway = false;      // MASK with a constant alpha below the cutoff
    };

    double extNumber(const tg::ExtensionMap &ext, const char *name, const char *key, double def,
                     const std::string &ptr) const {
        auto it = ext.find(name);
        if (it == ext.end() || !it->second.IsObject() || !it->second.Has(key)) return def;
        const tg::Value &v = it->second.Get(key);
        if (!v.IsNumber()) fail(ptr + "/extensions/" + name + "/" + key, "not a number");
        double d = v.GetNumberAsDouble();
        if (!std::isfinite(d)) fail(ptr + "/extensions/" + name + "/" + key, "not finite");
        return d;
    }

    void loadMaterials() {
        materials_.clear();
        for (size_t i = 0; i <= model_.materials.size(); ++i) {
            // The last entry is glTF's default material (primitives without one).
            tg::Material def;
            def.pbrMetallicRoughness.baseColorFactor = {1, 1, 1, 1};
            def.pbrMetallicRoughness.metallicFactor = 1;
            def.pbrMetallicRoughness.roughnessFactor = 1;
            def.emissiveFactor = {0, 0, 0};
            const bool isDefault = i == model_.materials.size();
            const tg::Material &m = isDefault ? def : model_.materials[i];
            const std::string ptr = isDefault ? "" : "/materials/" + std::to_string(i);
            MaterialDesc md;
            md.type = "gltfpbr";
            md.name = "gltf:" + filename_ + (isDefault ? ":default" : ptr);
            md.loc = at(ptr);
            md.present = true;
            MaterialInfo info;
            const auto &pbr = m.pbrMetallicRoughness;
            std::vector<double> bc = pbr.baseColorFactor;
            if (bc.size() != 4) fail(ptr + "/pbrMetallicRoughness/baseColorFactor", "needs 4 numbers");
            for (double x : bc)
                if (!std::isfinite(x)) fail(ptr + "/pbrMetallicRoughness/baseColorFactor", "not finite");
            int set = -1;
            auto useSet = [&](int s, const std::string &where) {
                if (set >= 0 && s != set)
                    note(where + " reads TEXCOORD_" + std::to_string(s) + " while other textures of the material read TEXCOORD_" +
                         std::to_string(set) + ": Gradus gives a material one uv set, TEXCOORD_" + std::to_string(set));
                if (set < 0) set = s;
            };
            if (pbr.baseColorTexture.index >= 0) {
                int s;
                std::string name = makeTexture(pbr.baseColorTexture, pbr.baseColorTexture.texCoord,
                                               ptr + "/pbrMetallicRoughness/baseColorTexture", "spectrum", "rgb", true,
                                               {bc[0], bc[1], bc[2], bc[3]}, -1, &s);
                addTextureRef(md.params, "basecolor", name, md.loc);
                useSet(s, ptr + "/pbrMetallicRoughness/baseColorTexture");
            } else {
                addNumbers(md.params, "rgb", "basecolor", {bc[0], bc[1], bc[2]}, md.loc);
            }
            if (pbr.metallicRoughnessTexture.index >= 0) {
                // glTF: roughness in G, metallic in B (linear), each times its factor.
                const std::string tp = ptr + "/pbrMetallicRoughness/metallicRoughnessTexture";
                int s;
                std::array<double, 4> f = {1, pbr.roughnessFactor, pbr.metallicFactor, 1};
                addTextureRef(md.params, "roughness",
                              makeTexture(pbr.metallicRoughnessTexture, pbr.metallicRoughnessTexture.texCoord, tp,
                                          "float", "g", false, f, -1, &s),
                              md.loc);
                addTextureRef(md.params, "metallic",
                              makeTexture(pbr.metallicRoughnessTexture, pbr.metallicRoughnessTexture.texCoord, tp,
                                          "float", "b", false, f, -1, &s),
                              md.loc);
                useSet(s, tp);
            } else {
                addFloats(md.params, "roughness", {pbr.roughnessFactor}, md.loc);
                addFloats(md.params, "metallic", {pbr.metallicFactor}, md.loc);
            }
            if (m.normalTexture.index >= 0) {
                tg::TextureInfo ti;
                ti.index = m.normalTexture.index;
                ti.texCoord = m.normalTexture.texCoord;
                ti.extensions = m.normalTexture.extensions;
                int s;
                addTextureRef(md.params, "normalmap",
                              makeTexture(ti, ti.texCoord, ptr + "/normalTexture", "spectrum", "rgb", false, {1, 1, 1, 1},
                                          -1, &s),
                              md.loc);
                addFloats(md.params, "normalscale", {m.normalTexture.scale}, md.loc);
                useSet(s, ptr + "/normalTexture");
                info.normalMap = true;
            }
            double ior = extNumber(m.extensions, "KHR_materials_ior", "ior", 1.5, ptr);
            if (ior != 1.5) addFloats(md.params, "ior", {ior}, md.loc);
            double tr = extNumber(m.extensions, "KHR_materials_transmission", "transmissionFactor", 0, ptr);
            if (tr != 0) addFloats(md.params, "transmission", {tr}, md.loc);
            auto trExt = m.extensions.find("KHR_materials_transmission");
            if (trExt != m.extensions.end() && trExt->second.IsObject() && trExt->second.Has("transmissionTexture"))
                note(ptr + ": transmissionTexture is ignored (the transmission factor is used)");
            // Emission: emissiveFactor * KHR_materials_emissive_strength.
            double strength = extNumber(m.extensions, "KHR_materials_emissive_strength", "emissiveStrength", 1, ptr);
            if (m.emissiveFactor.size() != 3) fail(ptr + "/emissiveFactor", "needs 3 numbers");
            info.emission = Spectrum(m.emissiveFactor[0], m.emissiveFactor[1], m.emissiveFactor[2]) * strength;
            if (!(info.emission.r >= 0 && info.emission.g >= 0 && info.emission.b >= 0) || !info.emission.isFinite())
                fail(ptr + "/emissiveFactor", "emission must be finite and non-negative");
            if (m.emissiveTexture.index >= 0 && !info.emission.isBlack()) {
                int s;
                info.emissionTexture = makeTexture(m.emissiveTexture, m.emissiveTexture.texCoord, ptr + "/emissiveTexture",
                                                   "spectrum", "rgb", true, {1, 1, 1, 1}, -1, &s);
                useSet(s, ptr + "/emissiveTexture");
                noteOnce("emissive textures emit their mean over each triangle (piecewise constant emission)");
            }
            info.doubleSided = m.doubleSided;
            if (m.alphaMode == "MASK") {
                if (pbr.baseColorTexture.index >= 0) {
                    int s;
                    info.alphaTexture = makeTexture(pbr.baseColorTexture, pbr.baseColorTexture.texCoord,
                                                    ptr + "/pbrMetallicRoughness/baseColorTexture", "float", "a", false,
                                                    {bc[0], bc[1], bc[2], bc[3]}, Float(m.alphaCutoff), &s);
                } else {
                    info.cutAway = bc[3] < m.alphaCutoff;
                }
            } else if (m.alphaMode == "BLEND") {
                note(ptr + ": alphaMode BLEND is rendered opaque (Gradus has no partial coverage)");
            } else if (m.alphaMode != "OPAQUE") {
                fail(ptr + "/alphaMode", "unknown alphaMode \"" + m.alphaMode + "\"");
            }
            info.texCoord = set < 0 ? 0 : set;
            info.descIndex = int(desc_->materials.size());
            desc_->materials.push_back(std::move(md));
            materials_.push_back(info);
        }
    }

    // ---- node hierarchy
    static Transform NodeTransform(const tg::Node &n, const std::function<void(const std::string &, const std::string &)> &bad) {
        if (!n.matrix.empty()) {
            if (n.matrix.size() != 16) bad("/matrix", "needs 16 numbers");
            Float v[16];
            for (int r = 0; r < 4; ++r)
                for (int c = 0; c < 4; ++c) v[r * 4 + c] = n.matrix[c * 4 + r];  // glTF: column-major
            for (Float x : v)
                if (!std::isfinite(x)) bad("/matrix", "not finite");
            Matrix4 m(v);
            try {
                return Transform(m);
            } catch (const Error &) {
                bad("/matrix", "matrix is singular");
            }
        }
        Transform t;
        if (!n.translation.empty()) {
            if (n.translation.size() != 3) bad("/translation", "needs 3 numbers");
            t = Translate(Vec3(n.translation[0], n.translation[1], n.translation[2]));
        }
        if (!n.rotation.empty()) {
            if (n.rotation.size() != 4) bad("/rotation", "needs 4 numbers (x, y, z, w)");
            double x = n.rotation[0], y = n.rotation[1], z = n.rotation[2], w = n.rotation[3];
            double len = std::sqrt(x * x + y * y + z * z + w * w);
            if (!(len > 0) || !std::isfinite(len)) bad("/rotation", "not a unit quaternion");
            x /= len, y /= len, z /= len, w /= len;
            Matrix4 r(1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w), 0,  //
                      2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w), 0,  //
                      2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y), 0,  //
                      0, 0, 0, 1);
            t = t * Transform(r, r.transposed());
        }
        if (!n.scale.empty()) {
            if (n.scale.size() != 3) bad("/scale", "needs 3 numbers");
            if (!(n.scale[0] != 0 && n.scale[1] != 0 && n.scale[2] != 0) ||
                !std::isfinite(n.scale[0] * n.scale[1] * n.scale[2]))
                bad("/scale", "scale must be finite and non-zero");
            t = t * Scale(n.scale[0], n.scale[1], n.scale[2]);
        }
        return t;
    }

    struct NodeUse {
        int node;
        Transform world;
    };

    void traverse(const Transform &worldFromAsset) {
        std::vector<int> roots;
        int sceneIndex = 0;
        if (!model_.scenes.empty()) {
            int s = sceneIndex = model_.defaultScene >= 0 ? model_.defaultScene : 0;
            if (s >= int(model_.scenes.size())) fail("/scene", "scene " + std::to_string(s) + " does not exist");
            roots = model_.scenes[s].nodes;
        } else {
            std::vector<bool> child(model_.nodes.size(), false);
            for (const auto &n : model_.nodes)
                for (int c : n.children)
                    if (c >= 0 && c < int(child.size())) child[c] = true;
            for (size_t i = 0; i < model_.nodes.size(); ++i)
                if (!child[i]) roots.push_back(int(i));
            if (!roots.empty()) note("the file has no scenes; rendering all root nodes");
        }
        std::vector<bool> seen(model_.nodes.size(), false);
        std::function<void(int, const Transform &, const std::string &)> visit = [&](int ni, const Transform &parent,
                                                                                     const std::string &from) {
            if (ni < 0 || ni >= int(model_.nodes.size())) fail(from, "node " + std::to_string(ni) + " does not exist");
            const std::string ptr = "/nodes/" + std::to_string(ni);
            if (seen[ni]) fail(from, "node " + std::to_string(ni) + " is reached twice (the hierarchy must be a tree)");
            seen[ni] = true;
            const tg::Node &n = model_.nodes[ni];
            Transform world = parent * NodeTransform(n, [&](const std::string &p, const std::string &msg) { fail(ptr + p, msg); });
            if (n.mesh >= 0) {
                if (n.mesh >= int(model_.meshes.size())) fail(ptr + "/mesh", "mesh " + std::to_string(n.mesh) + " does not exist");
                meshUses_[n.mesh].push_back({ni, world});
            }
            if (n.camera >= 0) {
                if (n.camera >= int(model_.cameras.size()))
                    fail(ptr + "/camera", "camera " + std::to_string(n.camera) + " does not exist");
                cameraNodes_.push_back({ni, world});
            }
            auto le = n.extensions.find("KHR_lights_punctual");
            if (le != n.extensions.end() && le->second.IsObject() && le->second.Has("light")) {
                const tg::Value &li = le->second.Get("light");
                if (!li.IsNumber()) fail(ptr + "/extensions/KHR_lights_punctual/light", "not a light index");
                addLight(li.GetNumberAsInt(), world, ptr + "/extensions/KHR_lights_punctual/light");
            }
            if (!n.weights.empty() || n.skin >= 0) noteOnce("skins and morph targets are ignored (the bind pose is rendered)");
            for (size_t c = 0; c < n.children.size(); ++c) visit(n.children[c], world, ptr + "/children/" + std::to_string(c));
        };
        const std::string rootPtr = model_.scenes.empty() ? std::string("/nodes") : "/scenes/" + std::to_string(sceneIndex) + "/nodes";
        for (size_t r = 0; r < roots.size(); ++r) visit(roots[r], worldFromAsset, rootPtr + "/" + std::to_string(r));
        if (!model_.animations.empty()) noteOnce("animations are ignored (the static pose is rendered)");
    }

    void noteOnce(const std::string &msg) {
        if (noted_.insert(msg).second) note(msg);
    }

    // ---- punctual lights
    void addLight(int li, const Transform &world, const std::string &from) {
        if (li < 0 || li >= int(model_.lights.size())) fail(from, "light " + std::to_string(li) + " does not exist");
        const tg::Light &l = model_.lights[li];
        const std::string ptr = "/extensions/KHR_lights_punctual/lights/" + std::to_string(li);
        Spectrum color(1);
        if (!l.color.empty()) {
            if (l.color.size() != 3) fail(ptr + "/color", "needs 3 numbers");
            color = Spectrum(l.color[0], l.color[1], l.color[2]);
        }
        // Photometric values are used as radiometric ones: 1 cd (point, spot) is
        // an intensity of 1, 1 lux (directional) an irradiance of 1, the same
        // scale as emissive materials (1 nit = radiance 1).
        Spectrum I = color * l.intensity;
        if (!I.isFinite() || !(I.r >= 0 && I.g >= 0 && I.b >= 0)) fail(ptr, "color * intensity must be finite and >= 0");
        LightDesc ld;
        ld.loc = at(ptr);
        ld.present = true;
        ld.worldFromLight = world;
        // glTF lights shine along the node's -Z.
        if (l.type == "point") {
            ld.type = "point";
            addNumbers(ld.params, "rgb", "I", {I.r, I.g, I.b}, ld.loc);
        } else if (l.type == "spot") {
            ld.type = "spot";
            double inner = l.spot.innerConeAngle, outer = l.spot.outerConeAngle;
            if (!(inner >= 0 && inner < outer && outer <= Pi / 2 + 1e-9))
                fail(ptr + "/spot", "cone angles need 0 <= innerConeAngle < outerConeAngle <= pi/2");
            addNumbers(ld.params, "rgb", "I", {I.r, I.g, I.b}, ld.loc);
            addNumbers(ld.params, "point3", "to", {0, 0, -1}, ld.loc);
            addFloats(ld.params, "coneangle", {Degrees(outer)}, ld.loc);
            addFloats(ld.params, "conedeltaangle", {Degrees(outer - inner)}, ld.loc);
            addString(ld.params, "falloff", "gltf", ld.loc);
        } else if (l.type == "directional") {
            ld.type = "distant";
            addNumbers(ld.params, "rgb", "L", {I.r, I.g, I.b}, ld.loc);
            addNumbers(ld.params, "point3", "to", {0, 0, -1}, ld.loc);
        } else {
            fail(ptr + "/type", "unknown light type \"" + l.type + "\" (known: point, spot, directional)");
        }
        if (l.range > 0) noteOnce("light ranges are ignored (lights fall off with the inverse square law only)");
        desc_->lights.push_back(std::move(ld));
        punctual_ = true;
    }

    // ---- meshes
    // The shapes of one primitive in mesh space (ShapeDesc without transform).
    bool buildPrimitive(int mi, int pi, ShapeDesc *sd, bool *emissive) {
        const tg::Primitive &p = model_.meshes[mi].primitives[pi];
        const std::string ptr = "/meshes/" + std::to_string(mi) + "/primitives/" + std::to_string(pi);
        int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
        if (mode < TINYGLTF_MODE_TRIANGLES) {
            noteOnce("points and lines are not rendered (e.g. " + ptr + ")");
            return false;
        }
        if (mode > TINYGLTF_MODE_TRIANGLE_FAN) fail(ptr + "/mode", "invalid primitive mode " + std::to_string(mode));
        if (p.material < -1 || p.material >= int(model_.materials.size()))
            fail(ptr + "/material", "material " + std::to_string(p.material) + " does not exist");
        const MaterialInfo &mat = materials_[p.material < 0 ? model_.materials.size() : size_t(p.material)];
        auto attr = [&](const char *name) {
            auto it = p.attributes.find(name);
            return it == p.attributes.end() ? -1 : it->second;
        };
        int pos = attr("POSITION");
        if (pos < 0) fail(ptr + "/attributes", "primitive has no POSITION");
        AccessorData P = readAccessor(pos, {TINYGLTF_TYPE_VEC3}, ptr + "/attributes/POSITION");
        const size_t nv = P.count;
        std::vector<size_t> idx;
        if (p.indices >= 0) {
            const tg::Accessor *ia = p.indices < int(model_.accessors.size()) ? &model_.accessors[p.indices] : nullptr;
            if (ia && (ia->componentType == TINYGLTF_COMPONENT_TYPE_FLOAT || ia->normalized ||
                       ia->componentType == TINYGLTF_COMPONENT_TYPE_BYTE || ia->componentType == TINYGLTF_COMPONENT_TYPE_SHORT))
                fail("/accessors/" + std::to_string(p.indices) + "/componentType", "indices must be unsigned integers");
            AccessorData I = readAccessor(p.indices, {TINYGLTF_TYPE_SCALAR}, ptr + "/indices");
            idx.resize(I.count);
            for (size_t k = 0; k < I.count; ++k) {
                if (I.v[k] >= double(nv))
                    fail(ptr + "/indices", "index " + std::to_string(size_t(I.v[k])) + " (element " + std::to_string(k) +
                                               ") is out of range: POSITION has " + std::to_string(nv) + " vertices");
                idx[k] = size_t(I.v[k]);
            }
        } else {
            idx.resize(nv);
            for (size_t k = 0; k < nv; ++k) idx[k] = k;
        }
        std::vector<double> tri;  // triangle list
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            if (idx.size() % 3) fail(p.indices >= 0 ? ptr + "/indices" : ptr + "/attributes/POSITION",
                                     "triangle list of " + std::to_string(idx.size()) + " vertices (not a multiple of 3)");
            tri.assign(idx.begin(), idx.end());
        } else {
            for (size_t k = 2; k < idx.size(); ++k) {
                size_t a, b, c = idx[k];
                if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
                    a = idx[k - 2], b = idx[k - 1];
                    if (k % 2) std::swap(a, b);  // keep the winding of even triangles
                } else {
                    a = idx[0], b = idx[k - 1];
                }
                tri.insert(tri.end(), {double(a), double(b), double(c)});
            }
        }
        if (tri.empty()) return false;
        if (tri.size() / 3 > size_t(1) << 30) fail(ptr, "too many triangles");
        sd->type = "trianglemesh";
        sd->loc = at(ptr);
        sd->present = true;
        sd->material = mat.descIndex;
        FileLoc loc = sd->loc;
        std::vector<int> triIdx(tri.begin(), tri.end());
        addNumbers(sd->params, "integer", "indices", std::move(tri), loc);
        std::vector<double> pts = P.v;
        int nrm = attr("NORMAL");
        if (nrm >= 0) {
            AccessorData N = readAccessor(nrm, {TINYGLTF_TYPE_VEC3}, ptr + "/attributes/NORMAL");
            if (N.count != nv) fail(ptr + "/attributes/NORMAL", "NORMAL count differs from POSITION count");
            // Zero normals (invalid glTF) fall back to the face normal there.
            for (size_t k = 0; k < nv; ++k) {
                double *n = &N.v[3 * k];
                double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                if (!(len > 0)) {
                    nrm = -1;
                    noteOnce("zero-length normals in " + ptr + ": its face normals are used");
                    break;
                }
                for (int c = 0; c < 3; ++c) n[c] /= len;
            }
            if (nrm >= 0) addNumbers(sd->params, "normal", "N", std::move(N.v), loc);
        }
        std::string uvName = "TEXCOORD_" + std::to_string(mat.texCoord);
        int uvi = attr(uvName.c_str());
        std::vector<double> uv;
        if (uvi >= 0) {
            AccessorData U = readAccessor(uvi, {TINYGLTF_TYPE_VEC2}, ptr + "/attributes/" + uvName);
            if (U.count != nv) fail(ptr + "/attributes/" + uvName, uvName + " count differs from POSITION count");
            uv = U.v;
        }
        if (mat.normalMap) {
            int tan = attr("TANGENT");
            std::vector<double> S;
            if (tan >= 0) {
                AccessorData T = readAccessor(tan, {TINYGLTF_TYPE_VEC4}, ptr + "/attributes/TANGENT");
                if (T.count != nv) fail(ptr + "/attributes/TANGENT", "TANGENT count differs from POSITION count");
                for (size_t k = 0; k < nv; ++k) S.insert(S.end(), {T.v[4 * k], T.v[4 * k + 1], T.v[4 * k + 2]});
            } else if (!uv.empty()) {
                S = GenerateTangents(pts, uv, triIdx);
            }
            if (!S.empty()) addNumbers(sd->params, "vector3", "S", std::move(S), loc);
        }
        addNumbers(sd->params, "point3", "P", std::move(pts), loc);
        if (!uv.empty()) addNumbers(sd->params, "point2", "uv", std::move(uv), loc);
        if (!mat.alphaTexture.empty()) addTextureRef(sd->params, "alpha", mat.alphaTexture, loc);
        if (mat.cutAway) addFloats(sd->params, "alpha", {0}, loc);
        *emissive = !mat.emission.isBlack();
        return true;
    }

    // Per-vertex tangents where the file has none: the area-weighted sum of
    // the triangles' dp/du (from positions and uvs), as a normal map needs a
    // tangent frame that follows the texture's u axis.
    static std::vector<double> GenerateTangents(const std::vector<double> &P, const std::vector<double> &uv,
                                                const std::vector<int> &idx) {
        std::vector<double> S(P.size(), 0.0);
        for (size_t t = 0; t + 2 < idx.size(); t += 3) {
            const int a = idx[t], b = idx[t + 1], c = idx[t + 2];
            double e1[3], e2[3];
            for (int k = 0; k < 3; ++k) e1[k] = P[3 * b + k] - P[3 * a + k], e2[k] = P[3 * c + k] - P[3 * a + k];
            double du1 = uv[2 * b] - uv[2 * a], dv1 = uv[2 * b + 1] - uv[2 * a + 1];
            double du2 = uv[2 * c] - uv[2 * a], dv2 = uv[2 * c + 1] - uv[2 * a + 1];
            double det = du1 * dv2 - du2 * dv1;
            if (!(std::abs(det) > 1e-20)) continue;
            double r = 1 / det, sgn = det > 0 ? 1 : -1;
            for (int k = 0; k < 3; ++k) {
                // dp/du, weighted by |det| (uv-area) through r * |det| = sign.
                double d = (e1[k] * dv2 - e2[k] * dv1) * r * std::abs(det) * sgn;
                S[3 * a + k] += d, S[3 * b + k] += d, S[3 * c + k] += d;
            }
        }
        return S;
    }

    void placeMeshes() {
        for (auto &mu : meshUses_) {
            const int mi = mu.first;
            const auto &uses = mu.second;
            std::vector<ShapeDesc> prims;
            std::vector<bool> emits;
            for (size_t pi = 0; pi < model_.meshes[mi].primitives.size(); ++pi) {
                ShapeDesc sd;
                bool e = false;
                if (!buildPrimitive(mi, int(pi), &sd, &e)) continue;
                prims.push_back(std::move(sd));
                emits.push_back(e);
            }
            bool anyEmissive = std::find(emits.begin(), emits.end(), true) != emits.end();
            // A mesh used by several nodes becomes an object instance; emitting
            // meshes stay world shapes (area lights are not instanced).
            if (uses.size() > 1 && !anyEmissive) {
                InstanceDesc inst;
                inst.name = "gltf:" + filename_ + "/meshes/" + std::to_string(mi);
                inst.loc = at("/meshes/" + std::to_string(mi));
                inst.shapes = prims;
                desc_->instances[inst.name] = inst;
                for (const auto &u : uses) desc_->instanceUses.push_back({inst.name, u.world, inst.loc});
                continue;
            }
            for (const auto &u : uses)
                for (size_t k = 0; k < prims.size(); ++k) {
                    ShapeDesc sd = prims[k];
                    sd.worldFromObject = u.world;
                    if (emits[k]) {
                        const MaterialInfo &mat = materialOf(sd.material);
                        EntityDesc al;
                        al.type = "diffuse";
                        al.loc = sd.loc;
                        al.present = true;
                        addNumbers(al.params, "rgb", "L", {mat.emission.r, mat.emission.g, mat.emission.b}, sd.loc);
                        addBool(al.params, "twosided", mat.doubleSided, sd.loc);
                        if (!mat.emissionTexture.empty()) addTextureRef(al.params, "Lmap", mat.emissionTexture, sd.loc);
                        sd.areaLight = int(desc_->areaLights.size());
                        desc_->areaLights.push_back(std::move(al));
                        emissive_ = true;
                    }
                    desc_->shapes.push_back(std::move(sd));
                }
        }
        // World bounds of the asset (for a default camera).
        worldBounds_ = Bounds3();
        for (size_t i = firstShape_; i < desc_->shapes.size(); ++i) expandBounds(desc_->shapes[i]);
        for (const auto &use : desc_->instanceUses) {
            auto it = desc_->instances.find(use.name);
            if (it == desc_->instances.end()) continue;
            for (const auto &s : it->second.shapes) expandBounds(s, &use.worldFromInstance);
        }
    }

    void expandBounds(const ShapeDesc &s, const Transform *extra = nullptr) {
        const Param *P = nullptr;
        for (const auto &p : s.params.all())
            if (p.name == "P") P = &p;
        if (!P) return;
        Transform w = extra ? *extra * s.worldFromObject : s.worldFromObject;
        for (size_t k = 0; k + 2 < P->numbers.size(); k += 3)
            worldBounds_.expand(w.applyPoint(Point3(P->numbers[k], P->numbers[k + 1], P->numbers[k + 2])));
    }

    const MaterialInfo &materialOf(int descIndex) const {
        for (const auto &m : materials_)
            if (m.descIndex == descIndex) return m;
        return materials_.back();
    }

    // ---- camera
    void chooseCamera(bool wholeScene) {
        const NodeUse *chosen = nullptr;
        std::string names;
        for (const auto &cn : cameraNodes_) {
            const tg::Node &n = model_.nodes[cn.node];
            const tg::Camera &c = model_.cameras[n.camera];
            names += (names.empty() ? "" : ", ") + (c.name.empty() ? n.name : c.name);
            if (opts_.camera.empty() ? !chosen : (c.name == opts_.camera || n.name == opts_.camera)) {
                if (!chosen) chosen = &cn;
            }
        }
        if (!opts_.camera.empty() && !chosen)
            throw Error(at0(), "no camera named \"" + opts_.camera + "\"" +
                                   (names.empty() ? " (the file has no cameras)" : " (cameras: " + names + ")"));
        CameraDesc &cd = desc_->camera;
        cd = CameraDesc();
        cd.type = "perspective";
        cd.present = true;
        if (chosen) {
            const tg::Node &n = model_.nodes[chosen->node];
            const tg::Camera &c = model_.cameras[n.camera];
            const std::string ptr = "/cameras/" + std::to_string(n.camera);
            cd.loc = at(ptr);
            if (c.type != "perspective")
                throw UnsupportedError(cd.loc, "glTF camera type \"" + c.type + "\" (only perspective cameras)");
            double yfov = c.perspective.yfov;
            if (!(yfov > 0 && yfov < Pi)) fail(ptr + "/perspective/yfov", "yfov must be in (0, pi)");
            addFloats(cd.params, "yfov", {Degrees(yfov)}, cd.loc);
            if (c.perspective.aspectRatio > 0 && std::isfinite(c.perspective.aspectRatio))
                cameraAspect_ = Float(c.perspective.aspectRatio);
            // glTF cameras look along -Z with +Y up (right-handed); Gradus' camera
            // space looks along +Z with +X right and +Y up: flip z.
            cd.cameraFromWorld = Scale(1, 1, -1) * chosen->world.inverse();
        } else {
            // Default: the bounds seen from +Z (glTF's front), 45 degrees vertically.
            Bounds3 b = worldBounds_;
            if (b.empty()) b.expand(Point3(0, 0, 0));
            Point3 c;
            Float r;
            b.boundingSphere(&c, &r);
            r = std::max<Float>(r, 1e-3);
            Float d = r / std::sin(Radians(22.5)) * 1.05;
            cd.loc = at0();
            addFloats(cd.params, "yfov", {45}, cd.loc);
            cd.cameraFromWorld = LookAt(c + Vec3(0, 0, d), c, Vec3(0, 1, 0));
            // LookAt builds pbrt-v3's left-handed view (image x = camera x = cross(up, dir)):
            // seen from +Z that is world -X; mirror x so that world +X is to the right.
            cd.cameraFromWorld = Scale(-1, 1, 1) * cd.cameraFromWorld;
            if (wholeScene) note("no camera in the file: a default camera looks at the scene from +Z");
        }
    }

    std::string filename_;
    GltfOptions opts_;
    SceneDesc *desc_;
    std::shared_ptr<const std::string> file_, jsonLabel_;
    std::string json_;
    tg::Model model_;
    int imageBase_ = 0;
    std::vector<MaterialInfo> materials_;
    std::map<int, std::vector<NodeUse>> meshUses_;
    std::vector<NodeUse> cameraNodes_;
    std::set<std::string> noted_;
    Bounds3 worldBounds_;
    size_t firstShape_ = 0;
    bool emissive_ = false, punctual_ = false;
    Float cameraAspect_ = 0;
};

}  // namespace

bool IsGltfFile(const std::string &filename) {
    std::string l = Lower(filename);
    auto ends = [&](const char *s) {
        size_t n = std::strlen(s);
        return l.size() >= n && l.compare(l.size() - n, n, s) == 0;
    };
    return ends(".gltf") || ends(".glb");
}

SceneDesc LoadGltfScene(const std::string &filename, const GltfOptions &opts) {
    SceneDesc desc;
    desc.sceneDirectory = DirectoryOf(filename);
    Loader loader(filename, opts, &desc);
    FileLoc loc;
    loc.file = std::make_shared<const std::string>(filename);
    loader.load(loc);
    loader.addContent(Transform(), true, true);
    // Film: 480 rows at the camera's aspect ratio, else 640x480; <stem>.exr.
    desc.film.type = "image";
    desc.film.present = true;
    desc.film.loc = loc;
    Float aspect = loader.cameraAspect() > 0 ? loader.cameraAspect() : Float(640) / 480;
    Param p;
    p.type = "integer";
    p.loc = loc;
    p.name = "xresolution";
    p.numbers = {double(std::max(1L, std::lround(480 * aspect)))};
    desc.film.params.add(p);
    p.name = "yresolution";
    p.numbers = {480};
    desc.film.params.add(p);
    Param fn;
    fn.type = "string";
    fn.name = "filename";
    fn.loc = loc;
    fn.strings = {StemOf(filename) + ".exr"};
    desc.film.params.add(fn);
    // Without punctual lights, a uniform white environment (radiance 1) lights
    // the scene, emissive surfaces or not (glTF viewers light such files too).
    if (!loader.hasPunctualLights() && opts.defaultEnvironment) {
        LightDesc env;
        env.type = "infinite";
        env.present = true;
        env.loc = loc;
        desc.lights.push_back(env);
        desc.notes.push_back(filename + ": no punctual lights: a uniform white environment lights the scene" +
                             (loader.hasEmitters() ? " besides its emissive surfaces" : "") +
                             " (--envmap none turns it off, --envmap FILE replaces it)");
    }
    return desc;
}

void AddGltfAsset(const std::string &filename, const Transform &worldFromAsset, const GltfOptions &opts,
                  bool useCamera, const FileLoc &loc, SceneDesc *desc) {
    Loader loader(filename, opts, desc);
    loader.load(loc);
    loader.addContent(worldFromAsset, useCamera, false);
}

}  // namespace gradus
