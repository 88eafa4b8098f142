// libFuzzer entry: the input bytes drive a generator of grammatical pbrt-v3
// scenes (camera, a film of at most 16x16, sampler, filter, a few textures,
// materials, shapes, lights; parameter values include extreme ones), which
// are parsed, built and rendered in-process for 1 spp with one of the
// registered integrators. gradus::Error is an expected outcome; any other
// exception, a crash, a sanitizer report, a hang (-timeout) or a NaN/Inf in
// the output image is a finding.
//   ./fuzz_scene -max_len=4096 corpus/   (seeds: tests/fuzz/corpus/fuzz_scene)
// FUZZ_SCENE_PRINT=1 prints each generated scene and its error, if any (to replay an input).
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "parser/scene_desc.h"
#include "job/job.h"
#include "integrators/registry.h"

namespace {

using gradus::IntegratorRegistry;

class Generator {
  public:
    explicit Generator(FuzzedDataProvider &fdp) : fdp_(fdp) {}

    std::string scene(std::string *integrator) {
        os_.precision(17);
        const auto &reg = IntegratorRegistry();
        *integrator = reg[fdp_.ConsumeIntegralInRange<size_t>(0, reg.size() - 1)].name;
        // Counts first, so that they do not depend on how many bytes the values use.
        const int ntex = fdp_.ConsumeIntegralInRange(0, 2), nmat = fdp_.ConsumeIntegralInRange(1, 3);
        const int nlights = fdp_.ConsumeIntegralInRange(0, 2), nshapes = fdp_.ConsumeIntegralInRange(0, 4);
        camera();
        os_ << "Film \"image\" \"integer xresolution\" [ " << fdp_.ConsumeIntegralInRange(1, 16)
            << " ] \"integer yresolution\" [ " << fdp_.ConsumeIntegralInRange(1, 16) << " ]";
        if (fdp_.ConsumeIntegralInRange(0, 7) == 0)
            os_ << " \"float cropwindow\" [ " << unit() << " " << unit() << " " << unit() << " " << unit() << " ]";
        os_ << "\n";
        static const char *samplers[] = {"random", "stratified", "halton", "sobol", "02sequence", "maxmindist"};
        os_ << "Sampler \"" << pick(samplers) << "\"\n";
        static const char *filters[] = {"box", "triangle", "gaussian", "mitchell", "sinc"};
        os_ << "PixelFilter \"" << pick(filters) << "\"";
        // Widths stay in [1e-30, 16] pixels: larger ones are a known finding (no upper bound:
        // 1e300 overflows the int sample bounds, 1e6 makes film tiles of gigabytes).
        if (coin()) os_ << " \"float xwidth\" [ " << width() << " ] \"float ywidth\" [ " << width() << " ]";
        os_ << "\nIntegrator \"" << *integrator << "\" \"integer maxdepth\" [ " << fdp_.ConsumeIntegralInRange(0, 8)
            << " ]";
        // mlt's bootstrap traces bootstrapsamples x (maxdepth + 1) paths (pbrt-v3's
        // default 100000 per depth): 900000 take more than the 10 s timeout under
        // ASan. A known cost (stress suite, furnace_d1000/mlt), capped here; so is
        // pmlt's and gmlt's (100000 bidirectional samples of all strategies).
        if (*integrator == "mlt" || *integrator == "pmlt" || *integrator == "gmlt")
            os_ << " \"integer bootstrapsamples\" [ " << fdp_.ConsumeIntegralInRange(1, 2000) << " ]";
        os_ << "\n";
        os_ << "WorldBegin\n";
        for (int i = 0; i < ntex; ++i) texture(i);
        ntex_ = ntex;
        for (int i = 0; i < nmat; ++i) material(i);
        for (int i = 0; i < nlights; ++i) light();
        for (int i = 0; i < nshapes; ++i) shape(nmat);
        os_ << "WorldEnd\n";
        return os_.str();
    }

  private:
    template <size_t N>
    const char *pick(const char *const (&names)[N]) {
        return names[fdp_.ConsumeIntegralInRange<size_t>(0, N - 1)];
    }
    bool coin() { return fdp_.ConsumeBool(); }
    double unit() { return fdp_.ConsumeIntegral<uint16_t>() / 65535.0; }  // 2 bytes a value

    // A number: mostly in [lo, hi], sometimes an extreme or special value, at most `cap`
    // in magnitude (positions, lengths, scales and the focal distance are capped: ray
    // origins beyond ~1.8e18 and the NaN directions of a focal distance of 1e200 abort
    // Embree, known findings).
    double value(double lo, double hi, double cap = HUGE_VAL) {
        static const double specials[] = {0, -0.0, 1, -1, 1e-30, -1e-30, 1e-8, 1e8, 1e30, -1e30,
                                          1e-300, 1e300, 0.5, 1.0000001, 3.0e38, 1e-45};
        double v;
        switch (fdp_.ConsumeIntegralInRange(0, 11)) {  // 1 in 6 is extreme: most scenes stay valid
            case 0: v = specials[fdp_.ConsumeIntegralInRange<size_t>(0, std::size(specials) - 1)]; break;
            case 1: v = fdp_.ConsumeFloatingPointInRange<double>(-1e6, 1e6); break;
            default: v = lo + (hi - lo) * unit(); break;
        }
        return std::abs(v) > cap ? std::copysign(cap, v) : v;
    }
    // Caps: three nested scales of 1e3 on a coordinate of 1e6 stay below 1e16.
    static constexpr double kPos = 1e6, kScale = 1e3;
    double width() { return fdp_.ConsumeBool() ? 1e-30 : 0.01 + 16 * unit(); }
    void vec3(double lo, double hi, double cap = HUGE_VAL) {
        os_ << value(lo, hi, cap) << " " << value(lo, hi, cap) << " " << value(lo, hi, cap);
    }
    void rgb(const char *name, double lo, double hi) {
        os_ << " \"rgb " << name << "\" [ " << value(lo, hi) << " " << value(lo, hi) << " " << value(lo, hi) << " ]";
    }
    void flt(const char *name, double lo, double hi, double cap = HUGE_VAL) {
        os_ << " \"float " << name << "\" [ " << value(lo, hi, cap) << " ]";
    }

    void camera() {
        os_ << "LookAt ";
        vec3(-5, 5, kPos);
        os_ << "  ";
        vec3(-1, 1);
        os_ << "  ";
        vec3(-1, 1);
        os_ << "\nCamera \"perspective\"";
        flt("fov", 1, 179);
        if (coin()) {
            flt("lensradius", 0, 2, kPos);
            flt("focaldistance", 0.01, 10, kPos);
        }
        if (fdp_.ConsumeIntegralInRange(0, 7) == 0)
            os_ << " \"float screenwindow\" [ " << value(-2, 0) << " " << value(0, 2) << " " << value(-2, 0) << " "
                << value(0, 2) << " ]";
        os_ << "\n";
    }

    // A spectrum parameter: a constant, or (when textures exist) a texture name.
    void spectrumParam(const char *name, double lo, double hi) {
        if (ntex_ > 0 && fdp_.ConsumeIntegralInRange(0, 3) == 0)
            os_ << " \"texture " << name << "\" \"s" << fdp_.ConsumeIntegralInRange(0, ntex_ - 1) << "\"";
        else
            rgb(name, lo, hi);
    }
    void floatParam(const char *name, double lo, double hi) {
        if (ntex_ > 0 && fdp_.ConsumeIntegralInRange(0, 3) == 0)
            os_ << " \"texture " << name << "\" \"f" << fdp_.ConsumeIntegralInRange(0, ntex_ - 1) << "\"";
        else
            flt(name, lo, hi);
    }

    void texture(int i) {
        static const char *types[] = {"constant", "scale", "mix", "checkerboard", "fbm", "wrinkled",
                                      "windy", "marble", "dots", "uv", "bilerp"};
        const char *t = pick(types);
        std::string s(t);
        // Every texture exists as float "f<i>" and spectrum "s<i>" (marble and uv are spectrum-only).
        for (int kind = 0; kind < 2; ++kind) {
            bool spectrum = kind == 1;
            std::string type = (!spectrum && (s == "marble" || s == "uv")) ? "constant" : s;
            os_ << "Texture \"" << (spectrum ? "s" : "f") << i << "\" \"" << (spectrum ? "spectrum" : "float")
                << "\" \"" << type << "\"";
            auto val = [&](const char *n) {
                if (spectrum) rgb(n, 0, 1);
                else flt(n, 0, 1);
            };
            if (type == "constant") val("value");
            else if (type == "scale" || type == "checkerboard") {
                val("tex1");
                val("tex2");
                if (type == "checkerboard" && coin()) os_ << " \"integer dimension\" [ 3 ]";
            } else if (type == "mix") {
                val("tex1");
                val("tex2");
                flt("amount", 0, 1);
            } else if (type == "bilerp") {
                val("v00");
                val("v01");
                val("v10");
                val("v11");
            } else if (type == "fbm" || type == "wrinkled") {
                os_ << " \"integer octaves\" [ " << fdp_.ConsumeIntegralInRange(0, 10) << " ]";
                flt("roughness", 0, 1);
            } else if (type == "marble") {
                flt("scale", 0, 10);
                flt("variation", 0, 1);
            } else if (type == "dots") {
                val("inside");
                val("outside");
            }
            if (coin() && (type == "checkerboard" || type == "dots" || type == "bilerp" || type == "uv")) {
                flt("uscale", -10, 10);
                flt("vscale", -10, 10);
            }
            os_ << "\n";
        }
    }

    void reflectances(std::initializer_list<const char *> names) {
        for (const char *n : names) spectrumParam(n, 0, 1);
    }
    void uvRoughness() {
        floatParam("uroughness", 0, 1);
        floatParam("vroughness", 0, 1);
    }
    void roughness(bool aniso) {
        if (aniso && coin()) {
            uvRoughness();
        } else if (!aniso || coin()) {
            floatParam("roughness", 0, 1);
        }
        if (coin()) os_ << " \"bool remaproughness\" \"" << (coin() ? "true" : "false") << "\"";
    }

    void material(int i) {
        static const char *types[] = {"matte", "plastic", "metal", "mirror", "glass", "uber",
                                      "substrate", "translucent", "mix", "none"};
        std::string t = pick(types);
        if (t == "mix" && i < 2) t = "matte";
        os_ << "MakeNamedMaterial \"m" << i << "\" \"string type\" [ \"" << t << "\" ]";
        if (t == "matte") {
            reflectances({"Kd"});
            if (coin()) floatParam("sigma", 0, 90);
        } else if (t == "plastic") {
            reflectances({"Kd", "Ks"});
            roughness(false);
        } else if (t == "metal") {
            if (coin()) spectrumParam("eta", 0, 4);
            if (coin()) spectrumParam("k", 0, 6);
            if (coin()) roughness(true);
        } else if (t == "mirror") {
            reflectances({"Kr"});
        } else if (t == "glass") {
            reflectances({"Kr", "Kt"});
            flt("index", 1, 3);
            if (coin()) uvRoughness();
        } else if (t == "uber") {
            reflectances({"Kd", "Ks", "Kr", "Kt", "opacity"});
            flt("index", 1, 3);
            roughness(true);
        } else if (t == "substrate") {
            reflectances({"Kd", "Ks"});
            uvRoughness();
        } else if (t == "translucent") {
            reflectances({"Kd", "Ks", "reflect", "transmit"});
            roughness(false);
        } else if (t == "mix") {
            os_ << " \"string materials\" [ \"m0\" \"m1\" ]";
            spectrumParam("amount", 0, 1);
        }
        if (ntex_ > 0 && t != "none" && t != "mix" && fdp_.ConsumeIntegralInRange(0, 5) == 0)
            os_ << " \"texture bumpmap\" \"f0\"";
        os_ << "\n";
    }

    void light() {
        static const char *types[] = {"point", "spot", "distant", "infinite"};
        std::string t = pick(types);
        os_ << "LightSource \"" << t << "\"";
        if (t == "infinite" || t == "distant") rgb("L", 0, 10);
        else rgb("I", 0, 10);
        if (t != "infinite" && coin()) {
            os_ << " \"point from\" [ ";
            vec3(-3, 3, kPos);
            os_ << " ]";
        }
        if ((t == "spot" || t == "distant") && coin()) {
            os_ << " \"point to\" [ ";
            vec3(-3, 3, kPos);
            os_ << " ]";
        }
        if (t == "spot" && coin()) {
            flt("coneangle", 0, 90);
            flt("conedeltaangle", 0, 30);
        }
        if (coin()) rgb("scale", 0, 2);
        os_ << "\n";
    }

    void transform() {
        int n = fdp_.ConsumeIntegralInRange(0, 3);
        for (int i = 0; i < n; ++i) {
            switch (fdp_.ConsumeIntegralInRange(0, 3)) {
                case 0: os_ << "  Translate "; vec3(-3, 3, kPos); break;
                case 1: os_ << "  Rotate " << value(-360, 360) << " "; vec3(-1, 1); break;
                case 2: os_ << "  Scale "; vec3(0.1, 3, kScale); break;
                default: os_ << "  ReverseOrientation"; break;
            }
            os_ << "\n";
        }
    }

    void points(int n, double lo, double hi) {
        os_ << " \"point P\" [";
        for (int i = 0; i < n; ++i) {
            os_ << " ";
            vec3(lo, hi, kPos);
        }
        os_ << " ]";
    }

    void shape(int nmat) {
        os_ << "AttributeBegin\n";
        transform();
        os_ << "  NamedMaterial \"m" << fdp_.ConsumeIntegralInRange(0, nmat - 1) << "\"\n";
        if (fdp_.ConsumeIntegralInRange(0, 2) == 0) {
            os_ << "  AreaLightSource \"diffuse\"";
            rgb("L", 0, 20);
            if (coin()) os_ << " \"bool twosided\" \"true\"";
            os_ << "\n";
        }
        static const char *types[] = {"sphere", "disk", "cylinder", "cone", "paraboloid", "hyperboloid",
                                      "trianglemesh", "trianglemesh", "loopsubdiv"};
        std::string t = pick(types);
        os_ << "  Shape \"" << t << "\"";
        if (t == "sphere") {
            flt("radius", 0.01, 3, kPos);
            if (coin()) {
                flt("zmin", -3, 0, kPos);
                flt("zmax", 0, 3, kPos);
                flt("phimax", 0, 360);
            }
        } else if (t == "disk") {
            flt("radius", 0.01, 3, kPos);
            if (coin()) flt("innerradius", 0, 1, kPos);
            if (coin()) flt("height", -2, 2, kPos);
        } else if (t == "cylinder" || t == "paraboloid") {
            flt("radius", 0.01, 3, kPos);
            flt("zmin", -2, 0, kPos);
            flt("zmax", 0, 2, kPos);
            if (coin()) flt("phimax", 0, 360);
        } else if (t == "cone") {
            flt("radius", 0.01, 3, kPos);
            flt("height", 0.01, 3, kPos);
        } else if (t == "hyperboloid") {
            os_ << " \"point p1\" [ ";
            vec3(-2, 2, kPos);
            os_ << " ] \"point p2\" [ ";
            vec3(-2, 2, kPos);
            os_ << " ]";
        } else {  // trianglemesh, loopsubdiv
            int nv = fdp_.ConsumeIntegralInRange(3, 6), nt = fdp_.ConsumeIntegralInRange(1, 6);
            points(nv, -2, 2);
            os_ << " \"integer indices\" [";
            for (int i = 0; i < 3 * nt; ++i) os_ << " " << fdp_.ConsumeIntegralInRange(0, nv - 1);
            os_ << " ]";
            if (t == "loopsubdiv") {
                os_ << " \"integer levels\" [ " << fdp_.ConsumeIntegralInRange(0, 3) << " ]";
            } else {
                if (coin()) {
                    os_ << " \"normal N\" [";
                    for (int i = 0; i < nv; ++i) {
                        os_ << " ";
                        vec3(-1, 1);
                    }
                    os_ << " ]";
                }
                if (coin()) {
                    os_ << " \"point2 uv\" [";
                    for (int i = 0; i < nv; ++i) os_ << " " << value(0, 1) << " " << value(0, 1);
                    os_ << " ]";
                }
            }
        }
        os_ << "\nAttributeEnd\n";
    }

    FuzzedDataProvider &fdp_;
    std::ostringstream os_;
    int ntex_ = 0;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    using namespace gradus;
    FuzzedDataProvider fdp(data, size);
    std::string integrator;
    std::string text = Generator(fdp).scene(&integrator);
    static const bool print = std::getenv("FUZZ_SCENE_PRINT") != nullptr;
    if (print) std::fprintf(stderr, "---- integrator %s\n%s", integrator.c_str(), text.c_str());
    try {
        SceneDesc desc = ParseString(text, "fuzz.pbrt", "/nonexistent");
        BuildOptions bo;
        bo.sppOverride = 1;
        bo.seed = 7;
        bo.quiet = true;
        RenderJob job = BuildRenderJob(desc, bo);
        RenderOptions ro;
        ro.spp = 1;
        ro.nthreads = 1;
        ro.quiet = true;
        RenderResult r = RenderJobImage(job, ro);
        const Image &img = r.image;
        for (size_t i = 0; i < img.data().size(); ++i)
            if (!std::isfinite(img.data()[i])) {
                const std::string &ch = img.channelNames()[i % img.channelNames().size()];
                std::fprintf(stderr, "fuzz_scene: non-finite value %g in channel %s (integrator %s)\n%s",
                             double(img.data()[i]), ch.c_str(), integrator.c_str(), text.c_str());
                std::abort();
            }
    } catch (const Error &e) {
        if (print) std::fprintf(stderr, "---- error: %s\n", e.what());
    }
    if (print) std::fprintf(stderr, "---- done\n");
    return 0;
}
