// reconstruct: screened-Poisson reconstruction of a gradient-domain render.
// Every failure prints "reconstruct: error: ..." on stderr and exits 1.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/error.h"
#include "image/image.h"
#include "reconstruction/reconstruction.h"

using namespace gradus;

namespace {

const char *kUsage = R"(usage: reconstruct IN.exr --outfile OUT.exr [options]
       reconstruct --primal P --dx DX --dy DY --outfile OUT.exr [options]

IN.exr holds layers primal, dx, dy (channels primal.R, dx.G, ...; dx(x,y) =
I(x+1,y) - I(x,y), the last column of dx and last row of dy are unused) and,
for --norm weighted, primal_var, dx_var, dy_var. An optional layer separated
(gradus' gradient integrators: light reaching the camera through ideal
specular scattering only, which takes no gradients) is part of primal: the
solve takes primal - separated and the output adds separated back; images
without it are reconstructed as before. With separate files, --primal-var,
--dx-var, --dy-var give the variances and --separated the separated light.

options:
  --outfile OUT         output image (EXR: R,G,B + metadata; a PNG preview is
                        written next to it as OUT with .png unless --no-png)
  --norm hybrid|l1|l2|weighted
                        hybrid (default): L1 at scales below --lowpass-sigma, the
                        primal's energy above them (unbiased there, as robust to
                        outlier gradients as L1). L1 (IRLS) is robust to outlier
                        gradients but biased: at short render times outliers carry
                        much of the light and L1 drops it (an image too dark). L2 is
                        unbiased but spreads outliers. Weighted: inverse-variance
                        weighted L2 (Rousselle et al. 2016), unbiased.
  --lowpass-sigma S     hybrid: the Gaussian scale in pixels (default 8)
  --alpha A             weight of the primal term (default 0.2; inf = primal)
  --l2-method exact|cg  L2 solver: DCT (default) or preconditioned CG
  --cg-iterations N     CG iterations per solve (default: 8 for L1, 2000 for L2 CG,
                        500 for weighted)
  --cg-tolerance T      stop CG when the residual falls by T (default 0 for L1,
                        1e-6 for L2 CG, 1e-5 for weighted)
  --irls-iterations N   L1: IRLS iterations (default 18)
  --irls-reg R          L1: initial IRLS regularisation (default 0.05)
  --irls-reg-factor F   L1: factor applied to it per iteration (default 0.5)
  --preconditioner jacobi|none   CG preconditioner (default jacobi)
  --init l2|primal      L1: start from the exact L2 solution (default) or the primal
  --preset NAME         hybrid (default), l1, l1-reference (20 IRLS x 50 plain CG from
                        the primal, as the reference implementation), l2, l2-cg, weighted;
                        later options override it
  --separated S         with --primal/--dx/--dy: the separated light (see above)
  --no-png              do not write the PNG preview
  --json                print a JSON report (residuals, iterations, seconds) on stdout
  --help                this text
)";

[[noreturn]] void Fail(const std::string &msg) { throw Error(msg); }

double ParseDouble(const std::string &opt, const std::string &v) {
    try {
        size_t n = 0;
        double d = std::stod(v, &n);
        if (n != v.size()) throw std::invalid_argument(v);
        return d;
    } catch (const std::exception &) {
        Fail("option " + opt + " expects a number, got '" + v + "'");
    }
}

int ParseInt(const std::string &opt, const std::string &v) {
    double d = ParseDouble(opt, v);
    if (d != std::floor(d) || d < 0 || d > 1e9) Fail("option " + opt + " expects a non-negative integer, got '" + v + "'");
    return int(d);
}

std::string Extension(const std::string &f) {
    size_t dot = f.find_last_of('.');
    size_t slash = f.find_last_of('/');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
    std::string e = f.substr(dot + 1);
    for (char &c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
    return e;
}

// The command line: positional arguments and --key -> value ("" for flags).
struct CommandLine {
    std::vector<std::string> pos;
    std::map<std::string, std::string> opt;
    bool has(const std::string &k) const { return opt.count(k) != 0; }
    const std::string &at(const std::string &k) const { return opt.at(k); }
};

CommandLine ParseCommandLine(int argc, char **argv) {
    CommandLine cl;
    const std::vector<std::string> valued = {
        "--outfile", "--norm", "--lowpass-sigma", "--alpha", "--l2-method", "--cg-iterations", "--cg-tolerance",
        "--irls-iterations", "--irls-reg", "--irls-reg-factor", "--preconditioner", "--init",
        "--preset", "--primal", "--dx", "--dy", "--primal-var", "--dx-var", "--dy-var", "--separated"};
    const std::vector<std::string> flags = {"--no-png", "--json", "--help"};
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        if (a.rfind("--", 0) == 0) {
            std::string key = a, val;
            size_t eq = a.find('=');
            if (eq != std::string::npos) key = a.substr(0, eq), val = a.substr(eq + 1);
            bool isValued = std::find(valued.begin(), valued.end(), key) != valued.end();
            bool isFlag = std::find(flags.begin(), flags.end(), key) != flags.end();
            if (!isValued && !isFlag) Fail("unknown option '" + key + "' (see --help)");
            if (isValued && eq == std::string::npos) {
                if (i + 1 >= argc) Fail("option " + key + " needs a value");
                val = argv[++i];
            }
            if (cl.opt.count(key)) Fail("option " + key + " given twice");
            cl.opt[key] = val;
        } else {
            cl.pos.push_back(a);
        }
    }
    return cl;
}

// Options: preset first, then individual overrides.
ReconstructionOptions OptionsFromCommandLine(const CommandLine &cl) {
    std::string preset = cl.has("--preset") ? cl.at("--preset") : "";
    if (!cl.has("--preset") && cl.has("--norm")) {
        ReconstructionNorm n = ParseReconstructionNorm(cl.at("--norm"));
        preset = ReconstructionNormName(n);
        if (n == ReconstructionNorm::L2 && cl.has("--l2-method") && cl.at("--l2-method") == "cg") preset = "l2-cg";
    }
    ReconstructionOptions o = ReconstructionOptions::Preset(preset.empty() ? "hybrid" : preset);
    if (cl.has("--norm")) o.norm = ParseReconstructionNorm(cl.at("--norm"));
    if (cl.has("--lowpass-sigma")) o.lowpassSigma = ParseDouble("--lowpass-sigma", cl.at("--lowpass-sigma"));
    if (cl.has("--alpha")) {
        const std::string &v = cl.at("--alpha");
        o.alpha = (v == "inf" || v == "infinity") ? INFINITY : ParseDouble("--alpha", v);
    }
    if (cl.has("--l2-method")) {
        const std::string &v = cl.at("--l2-method");
        if (v == "exact") o.l2Method = L2Method::Exact;
        else if (v == "cg") o.l2Method = L2Method::CG;
        else Fail("--l2-method must be exact or cg, got '" + v + "'");
    }
    if (cl.has("--cg-iterations")) o.cgIterations = ParseInt("--cg-iterations", cl.at("--cg-iterations"));
    if (cl.has("--cg-tolerance")) o.cgTolerance = ParseDouble("--cg-tolerance", cl.at("--cg-tolerance"));
    if (cl.has("--irls-iterations")) o.irlsIterations = ParseInt("--irls-iterations", cl.at("--irls-iterations"));
    if (cl.has("--irls-reg")) o.irlsRegInit = ParseDouble("--irls-reg", cl.at("--irls-reg"));
    if (cl.has("--irls-reg-factor")) o.irlsRegFactor = ParseDouble("--irls-reg-factor", cl.at("--irls-reg-factor"));
    if (cl.has("--preconditioner")) {
        const std::string &v = cl.at("--preconditioner");
        if (v == "jacobi") o.preconditioner = Preconditioner::Jacobi;
        else if (v == "none") o.preconditioner = Preconditioner::None;
        else Fail("--preconditioner must be jacobi or none, got '" + v + "'");
    }
    if (cl.has("--init")) {
        const std::string &v = cl.at("--init");
        if (v == "l2") o.initFromL2 = true;
        else if (v == "primal") o.initFromL2 = false;
        else Fail("--init must be l2 or primal, got '" + v + "'");
    }
    return o;
}

// --primal, --dx, --dy (and optionally the three variances) as separate images.
GradientImages ReadSeparateInputs(const CommandLine &cl, Image *source) {
    if (!cl.pos.empty()) Fail("give either one multi-layer input or --primal/--dx/--dy, not both");
    for (const char *k : {"--primal", "--dx", "--dy"})
        if (!cl.has(k)) Fail(std::string("missing ") + k + " (separate inputs need --primal, --dx and --dy)");
    *source = ReadImage(cl.at("--primal"));
    GradientImages in = GradientImagesFromImages(*source, ReadImage(cl.at("--dx")), ReadImage(cl.at("--dy")));
    if (cl.has("--separated")) {
        const Image sep = ReadImage(cl.at("--separated"));
        if (sep.width() != in.width || sep.height() != in.height)
            Fail("the separated image differs in size from the primal");
        in.separated = GradientImagesFromImages(sep, sep, sep).primal;
    }
    const int nv = int(cl.opt.count("--primal-var") + cl.opt.count("--dx-var") + cl.opt.count("--dy-var"));
    if (nv != 0 && nv != 3) Fail("give all of --primal-var, --dx-var and --dy-var, or none");
    if (nv == 3) {
        GradientImages v = GradientImagesFromImages(ReadImage(cl.at("--primal-var")), ReadImage(cl.at("--dx-var")),
                                                    ReadImage(cl.at("--dy-var")));
        if (v.width != in.width || v.height != in.height)
            Fail("the variance images differ in size from the primal");
        in.primalVar = v.primal;
        in.dxVar = v.dx;
        in.dyVar = v.dy;
    }
    return in;
}

// One multi-layer input (primal, dx, dy and optional variance layers).
GradientImages ReadLayeredInput(const CommandLine &cl, Image *source) {
    if (cl.pos.size() != 1) Fail(cl.pos.empty() ? "missing input (see --help)" : "more than one input given");
    for (const char *k : {"--primal-var", "--dx-var", "--dy-var", "--separated"})
        if (cl.has(k)) Fail(std::string(k) + " goes with --primal/--dx/--dy; a multi-layer input carries its own variance layers");
    Image img = ReadImage(cl.pos[0]);
    *source = img;
    try {
        return GradientImagesFromImage(img);
    } catch (const Error &e) {
        Fail(cl.pos[0] + ": " + e.what());
    }
}

// The result with the render's metadata and crop placement, plus the reconstruction's.
Image OutputImage(const ReconstructionResult &r, const ReconstructionOptions &o, const Image &source, int argc,
                  char **argv) {
    Image result = ResultToImage(r);
    const ReconstructionStats &st = r.stats;
    result.metadata = source.metadata;
    result.originX = source.originX, result.originY = source.originY;
    result.displayWidth = source.displayWidth, result.displayHeight = source.displayHeight;
    result.metadata["reconstruction"] = st.method;
    result.metadata["reconstruction_norm"] = ReconstructionNormName(o.norm);
    result.metadata["reconstruction_alpha"] = MetaValue::Double(o.alpha);
    result.metadata["reconstruction_seconds"] = MetaValue::Double(st.seconds);
    std::string cmd;
    for (int i = 0; i < argc; ++i) cmd += (i ? " " : "") + std::string(argv[i]);
    result.metadata["reconstruct_command_line"] = cmd;
    return result;
}

void PrintJsonReport(const ReconstructionResult &r, const ReconstructionOptions &o, const std::string &out,
                     const std::string &png) {
    const ReconstructionStats &st = r.stats;
    nlohmann::json j;
    j["outfile"] = out;
    if (!png.empty()) j["preview"] = png;
    j["width"] = r.width;
    j["height"] = r.height;
    j["norm"] = ReconstructionNormName(o.norm);
    j["method"] = st.method;
    j["alpha"] = std::isinf(o.alpha) ? nlohmann::json("inf") : nlohmann::json(o.alpha);
    j["seconds"] = st.seconds;
    j["irls_iterations"] = st.irlsIterations;
    j["cg_iterations"] = st.cgIterations;
    j["final_relative_residual"] = st.finalRelativeResidual;
    j["residuals"] = {{"primal_l2", st.primalL2}, {"gradient_l2", st.gradientL2},
                      {"primal_l1", st.primalL1}, {"gradient_l1", st.gradientL1}};
    j["objective"] = st.objective;
    std::cout << j.dump(2) << "\n";
}

int Run(int argc, char **argv) {
    const CommandLine cl = ParseCommandLine(argc, argv);
    if (cl.has("--help")) {
        std::cout << kUsage;
        return 0;
    }
    const ReconstructionOptions o = OptionsFromCommandLine(cl);
    if (!cl.has("--outfile")) Fail("missing --outfile (see --help)");
    const std::string out = cl.at("--outfile");
    const std::string ext = Extension(out);
    if (ext != "exr" && ext != "png" && ext != "pfm")
        Fail("--outfile '" + out + "' must end in .exr, .png or .pfm");

    // Inputs. The render's metadata and crop placement are carried through.
    Image source;
    const bool separate = cl.has("--primal") || cl.has("--dx") || cl.has("--dy");
    const GradientImages in = separate ? ReadSeparateInputs(cl, &source) : ReadLayeredInput(cl, &source);

    const ReconstructionResult r = Reconstruct(in, o);
    const Image result = OutputImage(r, o, source, argc, argv);
    WriteImage(out, result);
    std::string png;
    if (ext == "exr" && !cl.has("--no-png")) {
        png = out.substr(0, out.size() - 4) + ".png";
        WriteImage(png, result);
    }
    if (cl.has("--json")) PrintJsonReport(r, o, out, png);
    return 0;
}

}  // namespace

int main(int argc, char **argv) {
    try {
        return Run(argc, argv);
    } catch (const std::exception &e) {
        std::fprintf(stderr, "reconstruct: error: %s\n", e.what());
        return 1;
    }
}
