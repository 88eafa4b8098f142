// imgtool: compare, convert, inspect, merge and false-colour images; comparison pages.
// Exit status: 0 success, 1 a tolerance was exceeded (diff --tolerance),
// 2 an error (printed as "imgtool: error: ..." on stderr).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "image/image.h"
#include "image/metrics.h"
#include "job/checkpoint.h"

#include "compare_page.h"

using namespace gradus;
using nlohmann::json;

namespace {

struct CommandHelp {
    const char *name, *text;
};
const CommandHelp kHelp[] = {
    {"diff", R"(  diff A B      compare image A against the reference B (on R,G,B)
      --layer NAME            layer of A to compare (default: unprefixed R,G,B, else the
                              first layer with R,G,B); B uses the same layer if it has it
      --ref-layer NAME        layer of B to compare (default: as above)
      --discard-fraction F    ignore the fraction F in [0,1) of finite pixels with the
                              highest per-pixel relMSE (averaged over channels)
      --discard-count N       ignore N more of the highest-error pixels
      --metric M              relmse (default), mse, rmse or psnr
      --tolerance T           exit 1 when the metric exceeds T (for psnr: is below T)
      --epsilon E             relMSE offset, (X-R)^2/(R^2+E); default 0.001 (the papers')
      --outfile ERR.exr       write the per-pixel error image (R,G,B per-channel error,
                              "relmse" per-pixel mean, "excluded" mask)
      --json                  print one JSON object instead of text
    Metrics: MSE = mean (X-R)^2; RMSE = sqrt(MSE); PSNR = 10 log10(1/MSE) (peak 1.0);
    relMSE = mean over pixels and channels of (X-R)^2/(R^2+0.001). Pixels with NaN/Inf
    in A or B are counted, reported and excluded from every figure.
)"},
    {"convert", R"(  convert IN OUT                 EXR/PNG/PFM -> EXR/PNG/PFM (PNG: clamped 8-bit sRGB)
      --exposure EV           multiply by 2^EV
      --scale S               multiply by S
      --layer NAME            write only this layer, as R,G,B
)"},
    {"info", R"(  info FILE                      size, channels, NaN/Inf per layer, min/max/mean, metadata
                                 (a checkpoint: its render, pass range and sizes)
      --json                  print one JSON object
)"},
    {"merge", R"(  merge OUT IN1 [IN2 ...]        weighted average of images (every channel)
      --weights w1,w2,...     explicit weights (default: "spp" metadata of every
                              input when all have it, else equal weights)
      --allow-equal-seeds     merge renders that share a seed (correlated: refused by default)
    The output records its inputs (merged_inputs), the summed spp and render_seconds, and
    keeps the first input's other metadata.
  merge OUT.ckpt IN1.ckpt [IN2.ckpt ...]   exact sum of partial checkpoints of one render
    (gradus --passes A:B) whose pass ranges are disjoint and cover [0, N); resume OUT.ckpt
    with gradus to finish the image. Other renders, gaps and overlaps are refused.
)"},
    {"falsecolor", R"(  falsecolor A REF OUT.png       per-pixel relMSE of A vs REF as a colour ramp
      --max V                 value mapped to white (default: 99th percentile)
      --layer NAME            as for diff
      --ref-layer NAME        as for diff
)"},
    {"compare", R"(  compare REF A [B ...] -o DIR   interactive comparison page DIR/index.html (static files,
                                 opened from disk in a WebGL2 browser; no network, no server):
                                 exposure, sRGB / false-colour / relative-error views, synchronised
                                 zoom and pan, keys 1-9 and left/right flip, crops, relMSE, PSNR,
                                 means (as diff computes them) and every image's metadata
      -o, --out DIR           folder to write (created; the page's files in it are replaced)
      --labels R,A,B,...      names shown for REF, A, B, ... (default: the file names)
      --layer NAME            layer of every test image (default as for diff)
      --layers LA,LB,...      layer per test image (an empty entry: the default)
      --ref-layer NAME        layer of REF (default: its default layer)
      --exposure EV           initial exposure (default 0)
      --error-max V           initial top of the relative-error ramp (default: the geometric
                              mean over the images of their 99th percentile)
      --title TEXT            page title
      --discard-fraction F, --discard-count N, --epsilon E   as for diff (the figures only)
    The page embeds the linear RGB as half floats (6 bytes a pixel before compression).
    Relative-error view: per-pixel relMSE, mean over R,G,B of (X-R)^2/(R^2+E).
)"},
};

std::string Usage() {
    std::string u = "usage: imgtool <command> [arguments] [options]\n\ncommands:\n";
    for (const CommandHelp &h : kHelp) u += h.text;
    u += "  --help                         this text (also: imgtool <command> --help)\n"
         "exit status: 0 success, 1 tolerance exceeded (diff --tolerance), 2 error\n";
    return u;
}


// Parsed command line of one command: positionals and --options.
struct Args {
    std::vector<std::string> pos;
    std::map<std::string, std::string> opt;
    bool has(const std::string &k) const { return opt.count(k) > 0; }
};

// Options with a value; flags listed separately. Unknown options are errors.
Args Parse(const std::vector<std::string> &argv, const std::set<std::string> &valued,
           const std::set<std::string> &flags) {
    Args a;
    for (size_t i = 0; i < argv.size(); ++i) {
        const std::string &s = argv[i];
        if (s.size() > 2 && s.compare(0, 2, "--") == 0) {
            std::string key = s.substr(2), value;
            bool inlineValue = false;
            size_t eq = key.find('=');
            if (eq != std::string::npos) {
                value = key.substr(eq + 1);
                key = key.substr(0, eq);
                inlineValue = true;
            }
            if (valued.count(key)) {
                if (!inlineValue) {
                    if (i + 1 >= argv.size()) throw Error("option --" + key + " needs a value");
                    value = argv[++i];
                }
                if (a.opt.count(key)) throw Error("option --" + key + " given twice");
                a.opt[key] = value;
            } else if (flags.count(key) && !inlineValue) {
                a.opt[key] = "";
            } else {
                throw Error("unknown option \"" + s + "\" (see imgtool --help)");
            }
        } else if (s.size() > 1 && s[0] == '-' && !std::isdigit((unsigned char)s[1]) && s[1] != '.') {
            throw Error("unknown option \"" + s + "\" (see imgtool --help)");
        } else {
            a.pos.push_back(s);
        }
    }
    return a;
}

double ParseDouble(const std::string &what, const std::string &s) {
    try {
        size_t used = 0;
        double v = std::stod(s, &used);
        if (used == s.size() && std::isfinite(v)) return v;
    } catch (const std::exception &) {
    }
    throw Error("invalid number for " + what + ": \"" + s + "\"");
}

long long ParseCount(const std::string &what, const std::string &s) {
    try {
        size_t used = 0;
        long long v = std::stoll(s, &used);
        if (used == s.size() && v >= 0) return v;
    } catch (const std::exception &) {
    }
    throw Error("invalid count for " + what + ": \"" + s + "\"");
}

// "a,b,,c" -> {"a", "b", "", "c"}.
std::vector<std::string> SplitList(const std::string &s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ',')) out.push_back(item);
    if (!s.empty() && s.back() == ',') out.push_back("");
    return out;
}

std::string Num(double v) {
    std::ostringstream os;
    os.precision(6);
    os << v;
    return os.str();
}

json JsonNumber(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

CompareOptions CompareOpts(const Args &a) {
    CompareOptions o;
    if (a.has("layer")) o.layer = a.opt.at("layer");
    if (a.has("ref-layer")) o.refLayer = a.opt.at("ref-layer");
    if (a.has("discard-fraction"))
        o.discardFraction = ParseDouble("--discard-fraction", a.opt.at("discard-fraction"));
    if (a.has("discard-count")) o.discardCount = ParseCount("--discard-count", a.opt.at("discard-count"));
    if (a.has("epsilon")) o.relEpsilon = ParseDouble("--epsilon", a.opt.at("epsilon"));
    return o;
}

void NeedPositionals(const Args &a, size_t n, const std::string &cmd, bool atLeast = false) {
    if (atLeast ? a.pos.size() < n : a.pos.size() != n)
        throw Error(cmd + ": expected " + (atLeast ? "at least " : "") + std::to_string(n) +
                    " file argument(s), got " + std::to_string(a.pos.size()) +
                    " (see imgtool --help)");
}

int CmdDiff(const std::vector<std::string> &argv) {
    Args a = Parse(argv,
                   {"layer", "ref-layer", "discard-fraction", "discard-count", "tolerance", "metric", "outfile",
                    "epsilon"},
                   {"json"});
    NeedPositionals(a, 2, "diff");
    CompareOptions opts = CompareOpts(a);
    std::string metric = a.has("metric") ? a.opt.at("metric") : "relmse";
    MetricValue(ImageMetrics(), metric);  // validates the name before any work
    bool haveTol = a.has("tolerance");
    double tol = haveTol ? ParseDouble("--tolerance", a.opt.at("tolerance")) : 0;
    Image img = ReadImage(a.pos[0]), ref = ReadImage(a.pos[1]);
    ImageMetrics m = CompareImages(img, ref, opts);
    if (a.has("outfile")) WriteImage(a.opt.at("outfile"), ErrorImage(img, ref, opts, metric));
    double value = MetricValue(m, metric);
    bool pass = true;
    if (haveTol) pass = metric == "psnr" ? !(value < tol) : !(value > tol);

    if (a.has("json")) {
        json j;
        j["image"] = a.pos[0];
        j["reference"] = a.pos[1];
        j["layer"] = m.layer;
        j["reference_layer"] = m.refLayer;
        j["width"] = m.width;
        j["height"] = m.height;
        j["pixels"] = m.pixels;
        j["used_pixels"] = m.usedPixels;
        j["nonfinite_pixels"] = m.nonFinitePixels;
        j["nan_values"] = {{"image", m.imgNaN}, {"reference", m.refNaN}};
        j["inf_values"] = {{"image", m.imgInf}, {"reference", m.refInf}};
        j["discarded_pixels"] = m.discardedPixels;
        j["mse"] = JsonNumber(m.mse);
        j["rmse"] = JsonNumber(m.rmse);
        j["psnr"] = JsonNumber(m.psnr);  // null when MSE is 0
        j["relmse"] = JsonNumber(m.relmse);
        j["rel_epsilon"] = opts.relEpsilon;
        j["mean_image"] = JsonNumber(m.meanImg);
        j["mean_reference"] = JsonNumber(m.meanRef);
        j["mean_diff"] = JsonNumber(m.meanDiff);
        j["mean_rel_diff"] = JsonNumber(m.meanRelDiff);
        j["metric"] = metric;
        j["value"] = JsonNumber(value);
        if (haveTol) {
            j["tolerance"] = tol;
            j["pass"] = pass;
        }
        std::cout << j.dump() << "\n";
    } else {
        std::cout << a.pos[0] << " vs reference " << a.pos[1] << ": " << m.width << "x"
                  << m.height << ", layer \"" << m.layer << "\" vs \"" << m.refLayer << "\"\n";
        if (m.nonFinitePixels > 0)
            std::cout << "NaN/Inf: image " << m.imgNaN << " NaN, " << m.imgInf
                      << " Inf; reference " << m.refNaN << " NaN, " << m.refInf
                      << " Inf values; " << m.nonFinitePixels
                      << " pixels excluded from all figures\n";
        else
            std::cout << "NaN/Inf: none\n";
        if (m.discardedPixels > 0)
            std::cout << "discarded " << m.discardedPixels << " highest-error pixels\n";
        std::cout << "pixels used: " << m.usedPixels << " of " << m.pixels << "\n"
                  << "MSE     " << Num(m.mse) << "\n"
                  << "RMSE    " << Num(m.rmse) << "\n"
                  << "PSNR    " << Num(m.psnr) << " dB (peak 1.0)\n"
                  << "relMSE  " << Num(m.relmse) << " (mean of (X-R)^2/(R^2+" << opts.relEpsilon
                  << "))\n"
                  << "mean    image " << Num(m.meanImg) << ", reference " << Num(m.meanRef)
                  << ", difference " << Num(m.meanDiff) << " (" << Num(100 * m.meanRelDiff)
                  << "%)\n";
        if (haveTol)
            std::cout << (pass ? "PASS: " : "FAIL: ") << metric << " " << Num(value)
                      << (metric == "psnr" ? (pass ? " >= " : " < ") : (pass ? " <= " : " > "))
                      << "tolerance " << Num(tol) << "\n";
    }
    return pass ? 0 : 1;
}

int CmdConvert(const std::vector<std::string> &argv) {
    Args a = Parse(argv, {"exposure", "scale", "layer"}, {});
    NeedPositionals(a, 2, "convert");
    double factor = 1;
    if (a.has("scale")) factor *= ParseDouble("--scale", a.opt.at("scale"));
    if (a.has("exposure")) factor *= std::exp2(ParseDouble("--exposure", a.opt.at("exposure")));
    Image img = ReadImage(a.pos[0]);
    if (a.has("layer")) img = img.layerRGB(a.opt.at("layer"));
    if (factor != 1)
        for (float &v : img.data()) v = float(v * factor);
    WriteImage(a.pos[1], img);
    return 0;
}

int CmdInfo(const std::vector<std::string> &argv) {
    Args a = Parse(argv, {}, {"json"});
    NeedPositionals(a, 1, "info");
    if (IsCheckpointFile(a.pos[0])) {
        std::cout << a.pos[0] << ": Gradus checkpoint\n" << DescribeCheckpoint(ReadCheckpoint(a.pos[0]));
        return 0;
    }
    Image img = ReadImage(a.pos[0]);
    std::vector<ChannelStats> stats = ComputeChannelStats(img);
    // Per-layer NaN/Inf totals.
    std::vector<std::string> layers = img.layers();
    std::map<std::string, std::pair<long long, long long>> perLayer;
    for (const ChannelStats &s : stats) {
        size_t dot = s.name.rfind('.');
        std::string layer = dot == std::string::npos ? "" : s.name.substr(0, dot);
        perLayer[layer].first += s.nan;
        perLayer[layer].second += s.inf;
    }
    if (a.has("json")) {
        json j;
        j["file"] = a.pos[0];
        j["width"] = img.width();
        j["height"] = img.height();
        j["channels"] = img.channelNames();
        json jl = json::array();
        for (const std::string &l : layers)
            jl.push_back({{"name", l}, {"nan", perLayer[l].first}, {"inf", perLayer[l].second}});
        j["layers"] = jl;
        json jc = json::array();
        for (const ChannelStats &s : stats)
            jc.push_back({{"name", s.name}, {"min", s.min}, {"max", s.max}, {"mean", s.mean},
                          {"nan", s.nan}, {"inf", s.inf}, {"finite", s.finite}});
        j["channel_stats"] = jc;
        json meta = json::object();
        for (const auto &kv : img.metadata) {
            const MetaValue &v = kv.second;
            if (v.type() == MetaValue::Type::Int) meta[kv.first] = (long long)v.number();
            else if (v.type() == MetaValue::Type::Double) meta[kv.first] = JsonNumber(v.number());
            else meta[kv.first] = v.str();
        }
        j["metadata"] = meta;
        std::cout << j.dump() << "\n";
        return 0;
    }
    std::cout << a.pos[0] << ": " << img.width() << "x" << img.height() << ", "
              << img.numChannels() << " channels\n";
    for (const std::string &l : layers)
        std::cout << "layer \"" << l << "\": " << perLayer[l].first << " NaN, "
                  << perLayer[l].second << " Inf\n";
    std::cout << "channel          min           max           mean (finite values)\n";
    for (const ChannelStats &s : stats) {
        char line[256];
        std::snprintf(line, sizeof line, "%-14s %13.6g %13.6g %13.6g", s.name.c_str(), s.min,
                      s.max, s.mean);
        std::cout << line;
        if (s.nan || s.inf) std::cout << "  (" << s.nan << " NaN, " << s.inf << " Inf)";
        std::cout << "\n";
    }
    if (!img.metadata.empty()) {
        std::cout << "metadata:\n";
        for (const auto &kv : img.metadata) std::cout << "  " << kv.first << " = " << kv.second << "\n";
    }
    return 0;
}

// Partial checkpoints of one render (gradus --passes): exact sums of the
// accumulators into the checkpoint of the whole render.
int MergeCheckpointFiles(const Args &a) {
    std::vector<Checkpoint> parts;
    std::vector<std::string> names(a.pos.begin() + 1, a.pos.end());
    for (const auto &n : names) {
        if (!IsCheckpointFile(n)) throw Error("merge: " + n + " is not a checkpoint (checkpoints and images do not mix)");
        parts.push_back(ReadCheckpoint(n));
    }
    Checkpoint m = MergeCheckpoints(parts, names);
    WriteCheckpoint(a.pos[0], m);
    std::cout << "merged " << parts.size() << " checkpoints into " << a.pos[0] << ": passes [" << m.passBegin << ", "
              << m.passEnd << "), " << (m.complete ? "complete (gradus --resume " + a.pos[0] + " finishes the image)"
                                                   : "not complete")
              << "\n";
    return 0;
}

int CmdMerge(const std::vector<std::string> &argv) {
    Args a = Parse(argv, {"weights"}, {"allow-equal-seeds"});
    NeedPositionals(a, 2, "merge", true);
    if (IsCheckpointFile(a.pos[1])) return MergeCheckpointFiles(a);
    std::vector<Image> images;
    for (size_t i = 1; i < a.pos.size(); ++i) images.push_back(ReadImage(a.pos[i]));
    // Renders with the same seed (and scene) repeat the same random numbers:
    // their average is no better than one of them.
    std::map<std::string, size_t> seeds;
    for (size_t k = 0; k < images.size(); ++k) {
        auto it = images[k].metadata.find("seed");
        if (it == images[k].metadata.end()) continue;
        auto [at, fresh] = seeds.insert({it->second.str(), k});
        if (!fresh && !a.has("allow-equal-seeds"))
            throw Error("merge: " + a.pos[at->second + 1] + " and " + a.pos[k + 1] + " have the same seed " +
                        it->second.str() + " (correlated renders; --allow-equal-seeds merges them anyway)");
    }
    std::vector<double> weights;
    std::string source;
    if (a.has("weights")) {
        for (const std::string &item : SplitList(a.opt.at("weights")))
            weights.push_back(ParseDouble("--weights", item));
        if (weights.size() != images.size())
            throw Error("merge: " + std::to_string(weights.size()) + " weights given for " +
                        std::to_string(images.size()) + " images");
        source = "--weights";
    } else {
        bool fromSpp = false;
        weights = SppWeights(images, &fromSpp);
        source = fromSpp ? "spp metadata" : "equal (no spp metadata on every input)";
    }
    long long skipped = 0;
    Image out = MergeImages(images, weights, &skipped);
    // Provenance: the inputs and the summed render time.
    std::string inputs;
    double seconds = 0;
    bool allTimed = true;
    for (size_t k = 0; k < images.size(); ++k) {
        inputs += (k ? "; " : "") + a.pos[k + 1];
        auto sd = images[k].metadata.find("seed");
        if (sd != images[k].metadata.end()) inputs += " (seed " + sd->second.str() + ")";
        auto t = images[k].metadata.find("render_seconds");
        if (t == images[k].metadata.end()) allTimed = false;
        else seconds += t->second.number();
    }
    out.metadata["merged_inputs"] = inputs;
    if (allTimed) out.metadata["render_seconds"] = MetaValue::Double(seconds);
    out.metadata.erase("seed");
    WriteImage(a.pos[0], out);
    std::cout << "merged " << images.size() << " images into " << a.pos[0] << ", weights ("
              << source << "):";
    for (double w : weights) std::cout << " " << Num(w);
    std::cout << "\n";
    if (skipped > 0)
        std::cout << skipped << " NaN/Inf input values left out of their pixel's average\n";
    return 0;
}

int CmdFalsecolor(const std::vector<std::string> &argv) {
    Args a = Parse(argv, {"max", "layer", "ref-layer", "epsilon"}, {});
    NeedPositionals(a, 3, "falsecolor");
    CompareOptions opts = CompareOpts(a);
    Image img = ReadImage(a.pos[0]), ref = ReadImage(a.pos[1]);
    Image err = ErrorImage(img, ref, opts, "relmse");
    int ch = err.channelIndex("relmse"), ex = err.channelIndex("excluded");
    double maxValue;
    if (a.has("max")) {
        maxValue = ParseDouble("--max", a.opt.at("max"));
    } else {
        maxValue = ErrorQuantile(err, 0.99);
        if (!(maxValue > 0)) maxValue = 1;
    }
    // Excluded (NaN/Inf) pixels show as the NaN colour.
    size_t npix = size_t(err.width()) * size_t(err.height());
    for (size_t i = 0; i < npix; ++i)
        if (err.data()[i * err.numChannels() + ex] != 0.f)
            err.data()[i * err.numChannels() + ch] = NAN;
    WriteImage(a.pos[2], FalseColor(err, ch, maxValue));
    std::cout << "wrote " << a.pos[2] << ": per-pixel relMSE, white = " << Num(maxValue) << "\n";
    return 0;
}

int CmdCompare(std::vector<std::string> argv) {
    for (std::string &s : argv)
        if (s == "-o") s = "--out";
    Args a = Parse(argv,
                   {"out", "labels", "layer", "layers", "ref-layer", "exposure", "error-max", "title",
                    "discard-fraction", "discard-count", "epsilon"},
                   {});
    NeedPositionals(a, 2, "compare", true);
    if (!a.has("out")) throw Error("compare: the output folder is missing (-o DIR)");
    if (a.has("layer") && a.has("layers")) throw Error("compare: give --layer or --layers, not both");
    ComparePageOptions po;
    po.metrics = CompareOpts(a);
    if (a.has("exposure")) po.exposure = ParseDouble("--exposure", a.opt.at("exposure"));
    if (a.has("error-max")) {
        po.errorMax = ParseDouble("--error-max", a.opt.at("error-max"));
        if (!(po.errorMax > 0)) throw Error("compare: --error-max must be positive");
    }
    if (a.has("title")) po.title = a.opt.at("title");
    size_t n = a.pos.size();
    std::vector<std::string> labels(n), layers(n);
    if (a.has("labels")) {
        labels = SplitList(a.opt.at("labels"));
        if (labels.size() != n)
            throw Error("compare: " + std::to_string(labels.size()) + " labels given for " + std::to_string(n) +
                        " images (the reference included)");
    }
    if (a.has("layers")) {
        std::vector<std::string> l = SplitList(a.opt.at("layers"));
        if (l.size() != n - 1)
            throw Error("compare: " + std::to_string(l.size()) + " layers given for " + std::to_string(n - 1) +
                        " test images");
        std::copy(l.begin(), l.end(), layers.begin() + 1);
    }
    for (size_t k = 1; k < n; ++k)
        if (po.metrics.layer) layers[k] = *po.metrics.layer;
    if (po.metrics.refLayer) layers[0] = *po.metrics.refLayer;
    std::vector<ComparePageInput> inputs;
    for (size_t k = 0; k < n; ++k) inputs.push_back({a.pos[k], labels[k], layers[k]});
    const std::string dir = a.opt.at("out");
    ComparePageSummary s = WriteComparePage(dir, inputs, po);
    std::cout << "wrote " << dir << "/index.html (" << s.files.size() << " files, " << Num(s.bytes / 1e6)
              << " MB)\n";
    for (size_t k = 0; k < s.metrics.size(); ++k)
        std::cout << "  " << a.pos[k + 1] << ": relMSE " << Num(s.metrics[k].relmse) << ", PSNR "
                  << Num(s.metrics[k].psnr) << " dB\n";
    return 0;
}

bool WantsHelp(const std::vector<std::string> &args) {
    for (const std::string &s : args)
        if (s == "--help" || s == "-h") return true;
    return false;
}

constexpr int kExitError = 2;

}  // namespace

int main(int argc, char **argv) {
    std::vector<std::string> args(argv + 1, argv + argc);
    if (args.empty()) {
        std::cerr << Usage();
        return kExitError;
    }
    std::string cmd = args[0];
    if (WantsHelp(args)) {  // imgtool CMD --help: that command's text only
        for (const CommandHelp &h : kHelp)
            if (cmd == h.name) {
                std::cout << "usage: imgtool " << h.text << "exit status: 0 success, 1 tolerance exceeded, 2 error\n";
                return 0;
            }
        std::cout << Usage();
        return 0;
    }
    std::vector<std::string> rest(args.begin() + 1, args.end());
    try {
        if (cmd == "diff") return CmdDiff(rest);
        if (cmd == "convert") return CmdConvert(rest);
        if (cmd == "info") return CmdInfo(rest);
        if (cmd == "merge") return CmdMerge(rest);
        if (cmd == "falsecolor") return CmdFalsecolor(rest);
        if (cmd == "compare") return CmdCompare(rest);
        throw Error("unknown command \"" + cmd +
                    "\" (valid: diff, convert, info, merge, falsecolor, compare; see imgtool --help)");
    } catch (const std::exception &e) {
        std::cerr << "imgtool: error: " << e.what() << "\n";
        return kExitError;
    }
}
