// gradus: renders a pbrt-v3 scene.
#include <chrono>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>
#include <thread>

#include "core/error.h"
#include "core/stats.h"
#include "image/image.h"
#include "parser/scene_desc.h"
#include "render/scene_builder.h"

using namespace gradus;

namespace {

const char *kUsage =
    "usage: gradus scene.pbrt [options]\n"
    "  --outfile F          output image (.exr, .png, .pfm); default: the Film's filename\n"
    "  --nthreads N         worker threads (default: all cores)\n"
    "  --spp N              samples per pixel (overrides the Sampler's)\n"
    "  --seed S             random seed (default 0)\n"
    "  --time S             wall-clock budget in seconds (with --spp: whichever ends first)\n"
    "  --cropwindow x0 x1 y0 y1   render a sub-rectangle (fractions of the image)\n"
    "  --integrator NAME    override the scene's integrator (see --list-integrators)\n"
    "  --debugpixel x,y[,s] re-run the samples (or sample s) of one pixel single-threaded with the\n"
    "                       random numbers of the full render; prints vertices and contributions\n"
    "                       on stdout and writes no image\n"
    "  --quick              1/4 resolution and 1/8 of the samples\n"
    "  --stats              print the scene features after loading\n"
    "  --quiet              no progress bar or statistics\n"
    "  --list-integrators   print the available integrators\n"
    "  --describe NAME      print an integrator's parameters (name, type, default, help)\n";

[[noreturn]] void Usage(const std::string &msg) {
    std::fprintf(stderr, "gradus: %s\n%s", msg.c_str(), kUsage);
    std::exit(1);
}

long ParseInt(const std::string &opt, const char *s) {
    char *end;
    long v = std::strtol(s, &end, 10);
    if (*s == 0 || *end != 0) Usage(opt + " expects an integer, got \"" + s + "\"");
    return v;
}

double ParseDouble(const std::string &opt, const char *s) {
    char *end;
    double v = std::strtod(s, &end);
    if (*s == 0 || *end != 0) Usage(opt + " expects a number, got \"" + s + "\"");
    return v;
}

// --describe NAME: the integrator's parameter table, grouped by family.
int Describe(const std::string &name) {
    std::string valid;
    for (const auto &info : IntegratorRegistry()) {
        if (info.name == name) {
            std::printf("%s: %s\n\nParameters:\n%s", info.name.c_str(), info.description.c_str(),
                        FormatParams(info.parameters()).c_str());
            return 0;
        }
        valid += (valid.empty() ? "" : ", ") + info.name;
    }
    std::fprintf(stderr, "gradus: --describe: unknown integrator \"%s\" (available: %s)\n", name.c_str(),
                 valid.c_str());
    return 1;
}

}  // namespace

int main(int argc, char **argv) {
    BuildOptions bo;
    RenderOptions ro;
    std::string sceneFile;
    bool printStats = false;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        auto next = [&](int n = 1) {
            if (i + n >= argc) Usage(a + " needs " + std::to_string(n) + " value(s)");
            return argv[++i];
        };
        if (a == "--help" || a == "-h") {
            std::printf("%s", kUsage);
            return 0;
        } else if (a == "--list-integrators") {
            for (const auto &info : IntegratorRegistry())
                std::printf("%-8s %s\n", info.name.c_str(), info.description.c_str());
            return 0;
        } else if (a == "--describe") {
            return Describe(next());
        } else if (a == "--outfile") {
            bo.outfileOverride = next();
        } else if (a == "--nthreads") {
            ro.nthreads = int(ParseInt(a, next()));
        } else if (a == "--spp") {
            bo.sppOverride = int(ParseInt(a, next()));
            if (bo.sppOverride <= 0) Usage("--spp must be positive");
            ro.spp = bo.sppOverride;
        } else if (a == "--seed") {
            bo.seed = uint64_t(ParseInt(a, next()));
        } else if (a == "--debugpixel") {
            const char *v = next();
            int x, y, s = -1, n = 0;
            char extra;
            int got = std::sscanf(v, "%d,%d%n", &x, &y, &n);
            if (got == 2 && v[n] == ',') got = std::sscanf(v, "%d,%d,%d %c", &x, &y, &s, &extra) == 3 ? 3 : -1;
            else if (got == 2 && v[n] != 0) got = -1;
            if (got < 2 || x < 0 || y < 0 || (got == 3 && s < 0))
                Usage("--debugpixel expects x,y or x,y,s (non-negative integers), got \"" + std::string(v) + "\"");
            ro.debug = true;
            ro.debugPixel = {x, y};
            ro.debugSample = s;
        } else if (a == "--time") {
            ro.timeLimit = ParseDouble(a, next());
            if (!(ro.timeLimit > 0)) Usage("--time must be positive");
        } else if (a == "--cropwindow") {
            if (i + 4 >= argc) Usage("--cropwindow needs 4 values");
            bo.hasCrop = true;
            for (int k = 0; k < 4; ++k) bo.crop[k] = ParseDouble(a, argv[++i]);
        } else if (a == "--integrator") {
            bo.integratorOverride = next();
        } else if (a == "--quick") {
            bo.quick = true;
        } else if (a == "--quiet") {
            bo.quiet = ro.quiet = true;
        } else if (a == "--stats") {
            printStats = true;
        } else if (!a.empty() && a[0] == '-') {
            Usage("unknown option " + a);
        } else if (sceneFile.empty()) {
            sceneFile = a;
        } else {
            Usage("more than one scene file given");
        }
    }
    if (sceneFile.empty()) Usage("no scene file given");

    try {
        auto t0 = std::chrono::steady_clock::now();
        SceneDesc desc = ParseFile(sceneFile);
        RenderJob job = BuildRenderJob(desc, bo);
        if (printStats)  // notes about the scene integrator's parameters that an override ignores
            for (const auto &w : job.warnings) std::fprintf(stderr, "note: %s\n", w.c_str());
        double loadSec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (printStats) std::fprintf(stderr, "%s", job.scene->features.describe().c_str());
        if (ro.spp <= 0) ro.spp = job.sampler->samplesPerPixel();
        if (ro.timeLimit > 0 && bo.sppOverride <= 0) ro.spp = 0;  // time budget alone
        if (ro.debug && !job.film->sampleBounds().inside(ro.debugPixel))
            throw Error("--debugpixel (" + std::to_string(ro.debugPixel.x) + ", " + std::to_string(ro.debugPixel.y) +
                        ") lies outside the sampled pixels");
        InstallInterruptHandler();
        StatRegistry::get().reset();
        RenderResult res = RenderJobImage(job, ro);
        const RenderStats &rs = res.stats;
        Image &img = res.image;
        img.metadata["scene"] = sceneFile;
        if (ro.debug) {
            std::fprintf(stderr, "--debugpixel: no image written\n");
            return 0;
        }
        WriteImage(job.film->filename(), img);
        if (!ro.quiet) {
            std::fprintf(stderr,
                         "Scene loaded in %.2fs; rendered %d spp in %.2fs (%.3g camera samples/s)%s\n"
                         "Non-finite contributions discarded: %llu\n",
                         loadSec, rs.spp, rs.seconds, rs.cameraSamples / std::max(1e-9, rs.seconds),
                         rs.interrupted ? " [interrupted]" : (rs.timeLimited ? " [time budget]" : ""),
                         (unsigned long long)rs.nonFinite);
            std::fprintf(stderr, "Statistics:\n%s%s", FormatStats(StatRegistry::get().snapshot()).c_str(),
                         job.integrator->statistics().c_str());
            std::fprintf(stderr, "Wrote %s\n", job.film->filename().c_str());
        }
        return rs.interrupted ? 130 : 0;
    } catch (const std::exception &e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
}
