// gradus: renders a pbrt-v3 or glTF 2.0 scene.
#include <cerrno>
#include <cmath>
#include <limits>
#include <new>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>
#include <thread>

#include "core/error.h"
#include "core/provenance.h"
#include "core/stats.h"
#include "image/image.h"
#include "parser/gltf.h"
#include "parser/scene_desc.h"
#include "job/render_route.h"
#include "render/display.h"
#include "integrators/registry.h"

using namespace gradus;

namespace {

const char *kUsage =
    "usage: gradus scene.pbrt|scene.gltf|scene.glb [options]\n"
    "  --outfile F          output image (.exr, .png, .pfm); default: the Film's filename\n"
    "  --nthreads N         worker threads, 1 to 1024 (default: all cores)\n"
    "  --spp N              samples per pixel (overrides the Sampler's)\n"
    "  --seed S             random seed, a non-negative integer (default 0)\n"
    "  --time S             wall-clock budget in seconds for everything after scene loading\n"
    "                       (preprocess, passes, reconstruction; with --spp: whichever ends first)\n"
    "  --resolution WxH     film size in pixels (overrides the scene's; any scene format)\n"
    "  --camera NAME        glTF scenes: the camera (or camera node) to render (default: the first)\n"
    "  --cropwindow x0 x1 y0 y1   render a sub-rectangle (fractions of the image, in [0, 1])\n"
    "  --integrator NAME    override the scene's integrator (see --list-integrators)\n"
    "  --checkpoint FILE    write the render's accumulators to FILE every --checkpoint-interval\n"
    "                       seconds (default 300), at the end and on SIGINT/SIGTERM (which then\n"
    "                       stop after the current pass); atomic (FILE.tmp, fsync, rename)\n"
    "  --checkpoint-interval S   seconds between checkpoints (> 0)\n"
    "  --resume FILE        continue the render of a checkpoint (same scene, integrator, parameters,\n"
    "                       --spp and --seed; anything else is refused); a complete one only finishes\n"
    "  --passes A:B         render only passes [A, B) (one pass = one sample per pixel; vcm: an\n"
    "                       iteration) with the random numbers of the whole render; needs\n"
    "                       --checkpoint; writes no image unless --outfile is given. Partial\n"
    "                       checkpoints merge with imgtool merge OUT.ckpt IN.ckpt...\n"
    "  --param NAME=VALUE   set an integrator parameter (repeatable; see --describe NAME)\n"
    "  --debugpixel x,y[,s] re-run the samples (or sample s) of one pixel single-threaded with the\n"
    "                       random numbers of the full render; prints vertices and contributions\n"
    "                       on stdout and writes no image\n"
    "  --envmap FILE|none   light the scene with a lat-long HDR map (.exr, .hdr, .pfm) as an\n"
    "                       infinite light (pbrt-v3's mapping: the top row at the up axis, u = phi/2pi);\n"
    "                       the up axis is +z for pbrt scenes, +y for glTF scenes. glTF scenes without\n"
    "                       punctual lights get a uniform white environment instead: FILE replaces it,\n"
    "                       \"none\" turns it off\n"
    "  --envmap-scale S     multiplies the map's radiance (default 1)\n"
    "  --envmap-rotate DEG  turns the map DEG degrees about the up axis (+z pbrt, +y glTF),\n"
    "                       counterclockwise seen from above (right-handed)\n"
    "  --display-server HOST:PORT   stream the film while it renders to a viewer speaking tev's\n"
    "                       protocol (e.g. tev, listening on 127.0.0.1:14158), up to 4 updates/s;\n"
    "                       a viewer that cannot be reached is a warning, not an error\n"
    "  --display-layers     also stream the film's layers (primal, dx, ...)\n"
    "  --variance           gradient integrators also write primal_var, dx_var, dy_var\n"
    "                       (240 more bytes per pixel while rendering)\n"
    "  --quick              1/4 resolution and 1/8 of the samples\n"
    "  --stats              print the scene features after loading\n"
    "  --quiet              no progress bar or statistics\n"
    "  --list-integrators   print the available integrators\n"
    "  --describe NAME      print an integrator's parameters (name, type, default, help)\n"
    "  --version            print the version and git commit\n"
    "Exit status: 0 rendered, 1 error (message with file:line:column where it has one),\n"
    "130 interrupted (SIGINT/SIGTERM; the image rendered so far is written).\n";

// A bad command line: one line saying what is wrong, exit 1.
[[noreturn]] void Fail(const std::string &msg) {
    std::fprintf(stderr, "gradus: %s (see gradus --help)\n", msg.c_str());
    std::exit(1);
}

long long ParseInt(const std::string &opt, const char *s, long long lo, long long hi) {
    char *end;
    errno = 0;
    long long v = std::strtoll(s, &end, 10);
    if (*s == 0 || *end != 0 || errno == ERANGE) Fail(opt + " expects an integer, got \"" + std::string(s) + "\"");
    if (v < lo || v > hi)
        Fail(opt + " must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + std::to_string(v));
    return v;
}

double ParseDouble(const std::string &opt, const char *s) {
    char *end;
    double v = std::strtod(s, &end);
    if (*s == 0 || *end != 0 || !std::isfinite(v)) Fail(opt + " expects a finite number, got \"" + std::string(s) + "\"");
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

// What the command line asks for: the render's options, or an exit status
// when an informational option (--help, --version, ...) has been answered.
struct CommandLine {
    BuildOptions bo;
    RenderOptions ro;
    std::string sceneFile;
    GltfOptions gltfOpts;
    bool printStats = false, splitting = false;
    bool envScaleGiven = false, envRotateGiven = false;
    std::string commandLine;
    int exitStatus = -1;  // >= 0: exit with it, nothing to render
};

// Walks argv; next() returns the current option's value(s), failing when missing.
struct ArgCursor {
    int argc;
    char **argv;
    int i = 1;
    std::string a;  // the current option
    const char *next(int n = 1) {
        if (i + n >= argc) Fail(a + " needs " + std::to_string(n) + " value" + (n > 1 ? "s" : ""));
        return argv[++i];
    }
};

// --help, --list-integrators, --describe, --version: prints and returns the exit status; -1 otherwise.
int InfoOption(ArgCursor &arg) {
    const std::string &a = arg.a;
    if (a == "--help" || a == "-h") {
        std::printf("%s", kUsage);
        return 0;
    } else if (a == "--list-integrators") {
        for (const auto &info : IntegratorRegistry())
            std::printf("%-8s %s\n", info.name.c_str(), info.description.c_str());
        return 0;
    } else if (a == "--describe") {
        return Describe(arg.next());
    } else if (a == "--version") {
        std::printf("gradus %s (%s)\n", GradusVersion(), GradusGitCommit());
        return 0;
    }
    return -1;
}

void ParseDebugPixel(const char *v, RenderOptions &ro) {
    int x, y, s = -1, n = 0;
    char extra;
    int got = std::sscanf(v, "%d,%d%n", &x, &y, &n);
    if (got == 2 && v[n] == ',') got = std::sscanf(v, "%d,%d,%d %c", &x, &y, &s, &extra) == 3 ? 3 : -1;
    else if (got == 2 && v[n] != 0) got = -1;
    if (got < 2 || x < 0 || y < 0 || (got == 3 && s < 0))
        Fail("--debugpixel expects x,y or x,y,s (non-negative integers), got \"" + std::string(v) + "\"");
    ro.debug = true;
    ro.debugPixel = {x, y};
    ro.debugSample = s;
}

void ParseCropWindow(ArgCursor &arg, BuildOptions &bo) {
    if (arg.i + 4 >= arg.argc) Fail("--cropwindow needs 4 values");
    bo.hasCrop = true;
    for (int k = 0; k < 4; ++k) {
        bo.crop[k] = ParseDouble(arg.a, arg.argv[++arg.i]);
        if (bo.crop[k] < 0 || bo.crop[k] > 1) Fail("--cropwindow values must be in [0, 1], got " + std::string(arg.argv[arg.i]));
    }
    if (bo.crop[0] >= bo.crop[1] || bo.crop[2] >= bo.crop[3]) Fail("--cropwindow needs x0 < x1 and y0 < y1");
}

void ParseResolution(const char *v, BuildOptions &bo) {
    int w = 0, h = 0, n = 0;
    if (std::sscanf(v, "%dx%d%n", &w, &h, &n) != 2 || v[n] != 0 || w < 1 || h < 1 || w > (1 << 17) ||
        h > (1 << 17))
        Fail("--resolution expects WxH with W and H in [1, 131072], got \"" + std::string(v) + "\"");
    bo.resolution = {w, h};
}

void ParsePasses(const char *v, CommandLine &cl) {
    long long pa = -1, pb = -1;
    int n = 0;
    if (std::sscanf(v, "%lld:%lld%n", &pa, &pb, &n) != 2 || v[n] != 0 || pa < 0 || pb <= pa || pb > (1 << 30))
        Fail("--passes expects A:B with 0 <= A < B <= 2^30, got \"" + std::string(v) + "\"");
    cl.ro.passBegin = int(pa);
    cl.ro.passEnd = int(pb);
    cl.splitting = true;
}

// One render option or the scene file (fails on anything else).
void RenderOption(ArgCursor &arg, CommandLine &cl) {
    const std::string &a = arg.a;
    BuildOptions &bo = cl.bo;
    RenderOptions &ro = cl.ro;
    if (a == "--param") {
        bo.paramOverrides.push_back(arg.next());
    } else if (a == "--outfile") {
        bo.outfileOverride = arg.next();
    } else if (a == "--nthreads") {
        ro.nthreads = int(ParseInt(a, arg.next(), 1, 1024));
    } else if (a == "--spp") {
        bo.sppOverride = int(ParseInt(a, arg.next(), 1, 1 << 30));
        ro.spp = bo.sppOverride;
    } else if (a == "--seed") {
        bo.seed = uint64_t(ParseInt(a, arg.next(), 0, std::numeric_limits<long long>::max()));
    } else if (a == "--debugpixel") {
        ParseDebugPixel(arg.next(), ro);
    } else if (a == "--time") {
        const char *v = arg.next();
        ro.timeLimit = ParseDouble(a, v);
        if (!(ro.timeLimit > 0)) Fail("--time must be a positive number of seconds, got " + std::string(v));
    } else if (a == "--cropwindow") {
        ParseCropWindow(arg, bo);
    } else if (a == "--resolution") {
        ParseResolution(arg.next(), bo);
    } else if (a == "--checkpoint") {
        ro.checkpointFile = arg.next();
    } else if (a == "--checkpoint-interval") {
        ro.checkpointInterval = ParseDouble(a, arg.next());
        if (!(ro.checkpointInterval > 0)) Fail("--checkpoint-interval must be > 0 seconds");
    } else if (a == "--resume") {
        ro.resumeFile = arg.next();
    } else if (a == "--passes") {
        ParsePasses(arg.next(), cl);
    } else if (a == "--camera") {
        cl.gltfOpts.camera = arg.next();
    } else if (a == "--integrator") {
        bo.integratorOverride = arg.next();
    } else if (a == "--quick") {
        bo.quick = true;
    } else if (a == "--variance") {
        bo.variance = true;
    } else if (a == "--envmap") {
        bo.environment.map = arg.next();
        if (bo.environment.map.empty()) Fail("--envmap expects a file name or \"none\"");
    } else if (a == "--envmap-scale") {
        const char *v = arg.next();
        bo.environment.scale = ParseDouble(a, v);
        if (bo.environment.scale < 0) Fail("--envmap-scale must be >= 0, got " + std::string(v));
        cl.envScaleGiven = true;
    } else if (a == "--envmap-rotate") {
        bo.environment.rotateDegrees = ParseDouble(a, arg.next());
        cl.envRotateGiven = true;
    } else if (a == "--display-server") {
        ro.displayServer = arg.next();
    } else if (a == "--display-layers") {
        ro.displayLayers = true;
    } else if (a == "--quiet") {
        bo.quiet = ro.quiet = true;
    } else if (a == "--stats") {
        cl.printStats = true;
    } else if (!a.empty() && a[0] == '-') {
        Fail("unknown option " + a);
    } else if (cl.sceneFile.empty()) {
        cl.sceneFile = a;
    } else {
        Fail("more than one scene file given");
    }
}

// Options in order; the first informational option ends the parse with its status.
CommandLine ParseCommandLine(int argc, char **argv) {
    CommandLine cl;
    for (ArgCursor arg{argc, argv, 1, {}}; arg.i < argc; ++arg.i) {
        arg.a = argv[arg.i];
        cl.exitStatus = InfoOption(arg);
        if (cl.exitStatus >= 0) return cl;
        RenderOption(arg, cl);
    }
    if (cl.sceneFile.empty()) {
        std::fprintf(stderr, "gradus: no scene file given\n%s", kUsage);
        cl.exitStatus = 1;
        return cl;
    }
    if (cl.splitting && cl.ro.checkpointFile.empty())
        Fail("--passes needs --checkpoint FILE (the partial render's output)");
    if (cl.splitting && cl.ro.debug) Fail("--passes and --debugpixel exclude each other");
    if ((cl.envScaleGiven || cl.envRotateGiven) && !cl.bo.environment.addsLight())
        Fail(std::string(cl.envScaleGiven ? "--envmap-scale" : "--envmap-rotate") + " needs --envmap FILE");
    if (cl.ro.displayLayers && cl.ro.displayServer.empty()) Fail("--display-layers needs --display-server HOST:PORT");
    for (int i = 0; i < argc; ++i) cl.commandLine += (i ? " " : "") + std::string(argv[i]);
    return cl;
}

// Timing, statistics and the files written (unless --quiet).
void PrintSummary(const CommandLine &cl, const RenderJob &job, const RenderStats &rs, double loadSec,
                  bool wroteImage) {
    std::fprintf(stderr,
                 "Scene loaded in %.2fs; rendered %d spp in %.2fs (%.3g camera samples/s)%s\n"
                 "Non-finite contributions discarded: %llu\n",
                 loadSec, rs.spp, rs.seconds, rs.cameraSamples / std::max(1e-9, rs.seconds),
                 rs.interrupted ? " [interrupted]" : (rs.timeLimited ? " [time budget]" : ""),
                 (unsigned long long)rs.nonFinite);
    std::fprintf(stderr, "Statistics:\n%s%s", FormatStats(StatRegistry::get().snapshot()).c_str(),
                 job.integrator->statistics().c_str());
    if (wroteImage) std::fprintf(stderr, "Wrote %s\n", job.film->filename().c_str());
    if (!cl.ro.checkpointFile.empty()) std::fprintf(stderr, "Wrote checkpoint %s\n", cl.ro.checkpointFile.c_str());
}

// Loads the scene, renders and writes the image; returns the exit status.
int Render(CommandLine &cl) {
    BuildOptions &bo = cl.bo;
    RenderOptions &ro = cl.ro;
    // The output is checked before anything is loaded (again once the Film's name is known).
    if (!bo.outfileOverride.empty()) CheckWritableImagePath(bo.outfileOverride);
    if (!cl.gltfOpts.camera.empty() && !IsGltfFile(cl.sceneFile))
        Fail("--camera applies to glTF scenes (.gltf, .glb); pbrt scenes place glTF cameras with GltfAsset");
    // The viewer's address and the environment map too, before the scene.
    if (!ro.displayServer.empty()) {
        try {
            ParseDisplayAddress(ro.displayServer);
        } catch (const Error &e) {
            Fail(e.what());
        }
    }
    LoadEnvironmentMap(&bo.environment);
    double loadSec = 0;
    RenderJob job = LoadRenderJob(cl.sceneFile, cl.gltfOpts, bo, &loadSec);
    // Always said: e.g. scene parameters an --integrator override does not use.
    for (const auto &w : job.warnings) std::fprintf(stderr, "note: %s\n", w.c_str());
    if (cl.printStats) std::fprintf(stderr, "%s", job.scene->features.describe().c_str());
    ResolveSampleCount(job, bo, &ro);
    if (ro.debug && !job.film->sampleBounds().inside(ro.debugPixel))
        throw Error("--debugpixel (" + std::to_string(ro.debugPixel.x) + ", " + std::to_string(ro.debugPixel.y) +
                    ") lies outside the sampled pixels");
    InstallInterruptHandler();
    RenderResult res = RenderLoadedJob(job, ro, cl.sceneFile, cl.commandLine, loadSec);
    const RenderStats &rs = res.stats;
    if (ro.debug) {
        std::fprintf(stderr, "--debugpixel: no image written\n");
        return 0;
    }
    const bool writeImage = !cl.splitting || !bo.outfileOverride.empty();
    if (writeImage) WriteImage(job.film->filename(), res.image);
    if (!ro.quiet) PrintSummary(cl, job, rs, loadSec, writeImage);
    return rs.interrupted ? 130 : 0;
}

}  // namespace

int main(int argc, char **argv) {
    CommandLine cl = ParseCommandLine(argc, argv);
    if (cl.exitStatus >= 0) return cl.exitStatus;
    try {
        return Render(cl);
    } catch (const std::bad_alloc &) {
        std::fprintf(stderr, "gradus: out of memory\n");
        return 1;
    } catch (const std::exception &e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
}
