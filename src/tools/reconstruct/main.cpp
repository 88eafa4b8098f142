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
for --norm weighted, primal_var, dx_var, dy_var. With three separate files,
--primal-var, --dx-var, --dy-var give the variances.

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

int Run(int argc, char **argv) {
    std::vector<std::string> pos;
    std::map<std::string, std::string> opt;
    const std::vector<std::string> valued = {
        "--outfile", "--norm", "--lowpass-sigma", "--alpha", "--l2-method", "--cg-iterations", "--cg-tolerance",
        "--irls-iterations", "--irls-reg", "--irls-reg-factor", "--preconditioner", "--init",
        "--preset", "--primal", "--dx", "--dy", "--primal-var", "--dx-var", "--dy-var"};
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
            if (opt.count(key)) Fail("option " + key + " given twice");
            opt[key] = val;
        } else {
            pos.push_back(a);
        }
    }
    if (opt.count("--help")) {
        std::cout << kUsage;
        return 0;
    }

    // Options: preset first, then individual overrides.
    ReconstructionOptions o = ReconstructionOptions::Hybrid();
    std::string preset = opt.count("--preset") ? opt["--preset"] : "";
    if (!opt.count("--preset") && opt.count("--norm")) {
        ReconstructionNorm n = ParseReconstructionNorm(opt["--norm"]);
        preset = ReconstructionNormName(n);
        if (n == ReconstructionNorm::L2 && opt.count("--l2-method") && opt["--l2-method"] == "cg") preset = "l2-cg";
    }
    o = ReconstructionOptions::Preset(preset.empty() ? "hybrid" : preset);
    if (opt.count("--norm")) o.norm = ParseReconstructionNorm(opt["--norm"]);
    if (opt.count("--lowpass-sigma")) o.lowpassSigma = ParseDouble("--lowpass-sigma", opt["--lowpass-sigma"]);
    if (opt.count("--alpha")) {
        const std::string &v = opt["--alpha"];
        o.alpha = (v == "inf" || v == "infinity") ? INFINITY : ParseDouble("--alpha", v);
    }
    if (opt.count("--l2-method")) {
        const std::string &v = opt["--l2-method"];
        if (v == "exact") o.l2Method = L2Method::Exact;
        else if (v == "cg") o.l2Method = L2Method::CG;
        else Fail("--l2-method must be exact or cg, got '" + v + "'");
    }
    if (opt.count("--cg-iterations")) o.cgIterations = ParseInt("--cg-iterations", opt["--cg-iterations"]);
    if (opt.count("--cg-tolerance")) o.cgTolerance = ParseDouble("--cg-tolerance", opt["--cg-tolerance"]);
    if (opt.count("--irls-iterations")) o.irlsIterations = ParseInt("--irls-iterations", opt["--irls-iterations"]);
    if (opt.count("--irls-reg")) o.irlsRegInit = ParseDouble("--irls-reg", opt["--irls-reg"]);
    if (opt.count("--irls-reg-factor")) o.irlsRegFactor = ParseDouble("--irls-reg-factor", opt["--irls-reg-factor"]);
    if (opt.count("--preconditioner")) {
        const std::string &v = opt["--preconditioner"];
        if (v == "jacobi") o.preconditioner = Preconditioner::Jacobi;
        else if (v == "none") o.preconditioner = Preconditioner::None;
        else Fail("--preconditioner must be jacobi or none, got '" + v + "'");
    }
    if (opt.count("--init")) {
        const std::string &v = opt["--init"];
        if (v == "l2") o.initFromL2 = true;
        else if (v == "primal") o.initFromL2 = false;
        else Fail("--init must be l2 or primal, got '" + v + "'");
    }

    if (!opt.count("--outfile")) Fail("missing --outfile (see --help)");
    const std::string out = opt["--outfile"];
    const std::string ext = Extension(out);
    if (ext != "exr" && ext != "png" && ext != "pfm")
        Fail("--outfile '" + out + "' must end in .exr, .png or .pfm");

    // Inputs. The render's metadata and crop placement are carried through.
    GradientImages in;
    Image source;
    const bool separate = opt.count("--primal") || opt.count("--dx") || opt.count("--dy");
    if (separate) {
        if (!pos.empty()) Fail("give either one multi-layer input or --primal/--dx/--dy, not both");
        for (const char *k : {"--primal", "--dx", "--dy"})
            if (!opt.count(k)) Fail(std::string("missing ") + k + " (separate inputs need --primal, --dx and --dy)");
        source = ReadImage(opt["--primal"]);
        in = GradientImagesFromImages(source, ReadImage(opt["--dx"]), ReadImage(opt["--dy"]));
        const int nv = int(opt.count("--primal-var") + opt.count("--dx-var") + opt.count("--dy-var"));
        if (nv != 0 && nv != 3) Fail("give all of --primal-var, --dx-var and --dy-var, or none");
        if (nv == 3) {
            GradientImages v = GradientImagesFromImages(ReadImage(opt["--primal-var"]), ReadImage(opt["--dx-var"]),
                                                        ReadImage(opt["--dy-var"]));
            if (v.width != in.width || v.height != in.height)
                Fail("the variance images differ in size from the primal");
            in.primalVar = v.primal;
            in.dxVar = v.dx;
            in.dyVar = v.dy;
        }
    } else {
        if (pos.size() != 1) Fail(pos.empty() ? "missing input (see --help)" : "more than one input given");
        for (const char *k : {"--primal-var", "--dx-var", "--dy-var"})
            if (opt.count(k)) Fail(std::string(k) + " goes with --primal/--dx/--dy; a multi-layer input carries its own variance layers");
        Image img = ReadImage(pos[0]);
        source = img;
        try {
            in = GradientImagesFromImage(img);
        } catch (const Error &e) {
            Fail(pos[0] + ": " + e.what());
        }
    }

    ReconstructionResult r = Reconstruct(in, o);
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
    WriteImage(out, result);
    std::string png;
    if (ext == "exr" && !opt.count("--no-png")) {
        png = out.substr(0, out.size() - 4) + ".png";
        WriteImage(png, result);
    }

    if (opt.count("--json")) {
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
