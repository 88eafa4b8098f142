#include "job/job.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <thread>

#include <sys/resource.h>

#include "core/error.h"
#include "core/provenance.h"
#include "integrators/registry.h"
#include "job/checkpoint.h"

namespace gradus {

namespace {
double CpuSeconds() {
    rusage u;
    getrusage(RUSAGE_SELF, &u);
    return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}
// The process's own peak: /proc's VmHWM. getrusage's ru_maxrss survives
// execve, so a process started by a large parent (a benchmark script holding a
// mesh) would report the parent's size; it is the fallback without /proc.
double PeakRSSMegabytes() {
    if (FILE *f = std::fopen("/proc/self/status", "r")) {
        char line[256];
        long kb = -1;
        while (std::fgets(line, sizeof line, f))
            if (std::sscanf(line, "VmHWM: %ld kB", &kb) == 1) break;
        std::fclose(f);
        if (kb >= 0) return kb / 1024.0;
    }
    rusage u;
    getrusage(RUSAGE_SELF, &u);
    return u.ru_maxrss / 1024.0;  // ru_maxrss is in KiB on Linux
}
}  // namespace

// Media and BSSRDFs are refused by integrators that do not render them,
// naming the integrator and the scene part (never a silently wrong image).
constexpr const char *kMediaIntegrators = "path (pbrt-v3's volpath), bdpt, mbdpt and vcm (modes vcm and vc)";
static void RefuseUnhandledParts(const Integrator &integrator, const Scene &scene, const SceneDesc &desc,
                          const EntityDesc &idesc) {
    const FileLoc at = idesc.present ? idesc.loc : (desc.media.empty() ? FileLoc() : desc.media.front().loc);
    if (scene.features.media && !integrator.rendersMedia()) {
        const MediumDesc &m = desc.media.front();
        throw Error(at, "Integrator \"" + idesc.type + "\" does not render participating media (medium \"" + m.name +
                            "\" made at " + m.loc.str() + "); media render with " + kMediaIntegrators);
    }
    if (scene.features.subsurface && !integrator.rendersSubsurface()) {
        FileLoc mloc;
        for (const MaterialDesc &md : desc.materials)
            if (md.type == "subsurface" || md.type == "kdsubsurface") {
                mloc = md.loc;
                break;
            }
        throw Error(at, "Integrator \"" + idesc.type + "\" does not render subsurface scattering (material made at " +
                            mloc.str() + "); BSSRDFs render with path");
    }
    if (!scene.camera->hasImportance() && !integrator.rendersCamerasWithoutImportance())
        throw Error(idesc.present ? idesc.loc : desc.camera.loc,
                    "Integrator \"" + idesc.type + "\" does not render Camera \"" + desc.camera.type + "\" (made at " +
                        desc.camera.loc.str() + "), which has no importance function for light-to-camera "
                        "connections; it renders with path and bdpt (bdpt without its light-tracing strategies)");
}

namespace {

// pbrt-v3's "sppm" is vcm's merging-only mode (progressive photon mapping,
// vcm.h), which reads sppm's parameters (numiterations, radius, ...); pbrt-v3's
// defaults of 64 iterations and radius 1 are made explicit.
void MapPbrtSppm(EntityDesc *d) {
    if (d->type != "sppm" || std::none_of(IntegratorRegistry().begin(), IntegratorRegistry().end(),
                                          [](const IntegratorInfo &i) { return i.name == "vcm"; }))
        return;
    auto add = [&](const std::string &type, const std::string &name, double number, const std::string &str) {
        if (d->params.has(name)) return;
        Param p;
        p.type = type;
        p.name = name;
        p.loc = d->loc;
        if (type == "string")
            p.strings = {str};
        else
            p.numbers = {number};
        d->params.add(p);
    };
    add("integer", "numiterations", 64, "");
    add("float", "radius", 1, "");
    add("string", "mode", 0, "vm");
    d->type = "vcm";
}

}  // namespace

RenderJob BuildRenderJob(const SceneDesc &desc, const BuildOptions &opts) {
    RenderJob job;
    job.warnings = desc.notes;
    // Film.
    const EntityDesc &fd = desc.film;
    if (fd.present && fd.type != "image")
        throw Error(fd.loc, "unknown film \"" + fd.type + "\" (valid: image)");
    const ParamSet &fp = fd.params;
    Point2i res{fp.getInt("xresolution", 640), fp.getInt("yresolution", 480)};
    constexpr int kMaxSide = 1 << 17;
    for (const char *n : {"xresolution", "yresolution"}) {
        int v = n[0] == 'x' ? res.x : res.y;
        if (v <= 0 || v > kMaxSide)
            throw Error(fp.locOf(n, fd.loc), std::string("\"") + n + "\" must be in [1, " + std::to_string(kMaxSide) +
                                                 "], got " + std::to_string(v));
    }
    if (opts.resolution.x > 0 && opts.resolution.y > 0) res = opts.resolution;
    if (opts.quick) res = {std::max(1, res.x / 4), std::max(1, res.y / 4)};
    Float crop[4] = {0, 1, 0, 1};
    std::vector<Float> cw = fp.getFloats("cropwindow");
    if (!cw.empty()) {
        if (cw.size() != 4) throw Error(fp.locOf("cropwindow", fd.loc), "\"cropwindow\" needs 4 values");
        for (int i = 0; i < 4; ++i) crop[i] = cw[i];
    }
    if (opts.hasCrop)
        for (int i = 0; i < 4; ++i) crop[i] = opts.crop[i];
    for (int i = 0; i < 4; ++i) crop[i] = Clamp<Float>(crop[i], 0, 1);
    if (crop[0] > crop[1]) std::swap(crop[0], crop[1]);
    if (crop[2] > crop[3]) std::swap(crop[2], crop[3]);
    std::string filename = fp.getString("filename", "gradus.exr");
    Float scale = fp.getFloat("scale", 1);
    fp.getFloat("diagonal", 35);
    Float maxLum = fp.getFloat("maxsampleluminance", Infinity);
    if (std::isfinite(maxLum))
        throw UnsupportedError(fp.locOf("maxsampleluminance", fd.loc), "Film \"maxsampleluminance\" clamping");
    fp.checkUnused("Film \"image\"");
    if (!opts.outfileOverride.empty()) filename = opts.outfileOverride;
    if (opts.checkOutput) CheckWritableImagePath(filename);  // before any geometry is loaded or a sample rendered
    std::unique_ptr<Filter> filter = CreateFilter(desc.filter);
    try {
        job.film = std::make_unique<Film>(res, crop, std::move(filter), filename, scale);
    } catch (const Error &e) {  // a film too large for this machine: located at the resolution
        throw Error(fp.locOf("xresolution", fd.loc), e.what());
    }

    // Sampler.
    EntityDesc sdesc = desc.sampler;
    if (!sdesc.present) sdesc.type = "halton";
    int sppOverride = opts.sppOverride;
    job.sampler = CreateSampler(sdesc, opts.seed, sppOverride);
    if (opts.quick && sppOverride <= 0)
        job.sampler = CreateSampler(sdesc, opts.seed, std::max(1, job.sampler->samplesPerPixel() / 8));
    sdesc.params.checkUnused("Sampler \"" + sdesc.type + "\"");

    if (desc.accelerator.present) {
        // Embree replaces pbrt-v3's BVH/kd-tree; their tuning parameters are accepted and ignored.
        for (const auto &p : desc.accelerator.params.all()) p.used = true;
    }

    // Integrator.
    EntityDesc idesc = desc.integrator;
    if (!idesc.present) idesc.type = "path";
    bool overridden = !opts.integratorOverride.empty() && opts.integratorOverride != idesc.type;
    if (!opts.integratorOverride.empty()) idesc.type = opts.integratorOverride;
    MapPbrtSppm(&idesc);
    if (idesc.type == "volpath") idesc.type = "path";  // path renders media as pbrt-v3's volpath does
    ApplyParamOverrides(opts.paramOverrides, &idesc);
    job.integrator = CreateIntegrator(idesc);
    if (overridden) {
        // Parameters written for the scene's own integrator do not all apply to the override.
        for (const auto &p : idesc.params.all())
            if (!p.used) {
                job.warnings.push_back(p.loc.str() + ": parameter \"" + p.type + " " + p.name +
                                       "\" of Integrator \"" + desc.integrator.type + "\" is ignored by \"" +
                                       idesc.type + "\"");
                p.used = true;
            }
    }
    idesc.params.checkUnused("Integrator \"" + idesc.type + "\"");
    // Variance layers: --variance, or a gradient integrator's weighted reconstruction (which reads them).
    const Param *recon = idesc.params.find("reconstruction");
    job.film->setVarianceLayers(opts.variance || (recon && recon->strings.size() == 1 && recon->strings[0] == "weighted"));
    // An integrator with its own sample count (mlt's mutationsperpixel, vcm's
    // numiterations) keeps it unless --spp is given, carried by a "random" sampler
    // (a stratified one could round it; mlt draws no numbers from it, and pbrt-v3's
    // sppm ignores the scene's Sampler as well).
    if (const int n = job.integrator->defaultSamplesPerPixel(); n > 0 && sppOverride <= 0) {
        EntityDesc rd;
        rd.type = "random";
        rd.present = true;
        job.sampler = CreateSampler(rd, opts.seed, opts.quick ? std::max(1, n / 8) : n);
    }
    // pbrt-v3's integrator "pixelbounds": accepted when it covers the film, else
    // named as unsupported (never silently ignored).
    std::vector<int> pb = idesc.params.getInts("pixelbounds");
    if (!pb.empty()) {
        FileLoc at = idesc.params.locOf("pixelbounds", idesc.loc);
        if (pb.size() != 4) throw Error(at, "\"pixelbounds\" needs 4 values (x0 x1 y0 y1)");
        const Bounds2i &fb = job.film->pixelBounds();
        if (pb[0] > fb.pMin.x || pb[1] < fb.pMax.x || pb[2] > fb.pMin.y || pb[3] < fb.pMax.y)
            throw UnsupportedError(at, "Integrator \"pixelbounds\" that exclude film pixels (use --cropwindow)");
    }

    job.scene = BuildScene(desc, res);
    RefuseUnhandledParts(*job.integrator, *job.scene, desc, idesc);

    Metadata &m = job.provenance;
    auto entity = [](const EntityDesc &e, const std::string &type) {
        std::string r = e.params.resolved();
        return "\"" + type + "\"" + (r.empty() ? "" : " " + r);
    };
    m["camera"] = entity(desc.camera, desc.camera.present ? desc.camera.type : "perspective");
    m["sampler"] = entity(sdesc, sdesc.type);
    m["film"] = entity(fd, "image");
    m["pixelfilter"] = entity(desc.filter, desc.filter.present ? desc.filter.type : "box");
    m["integrator_parameters"] = entity(idesc, idesc.type);
    m["resolution"] = std::to_string(res.x) + "x" + std::to_string(res.y);
    m["cropwindow"] = std::to_string(crop[0]) + " " + std::to_string(crop[1]) + " " + std::to_string(crop[2]) +
                      " " + std::to_string(crop[3]);
    m["quick"] = MetaValue::Int(opts.quick ? 1 : 0);
    m["variance_layers"] = MetaValue::Int(job.film->varianceLayers() ? 1 : 0);
    InputFilesSummary in = InputFiles();
    m["scene_files"] = MetaValue::Int(in.files);
    m["scene_bytes"] = MetaValue::Int(int64_t(in.bytes));
    m["scene_hash"] = "fnv1a64:" + in.hash;
    return job;
}

std::string RenderIdentity(const RenderJob &job, const RenderOptions &opts) {
    // Everything the accumulated values depend on (not the output name, the
    // film's scale or the thread count).
    std::string id;
    for (const char *k : {"scene_hash", "camera", "sampler", "pixelfilter", "resolution", "cropwindow", "quick",
                          "integrator_parameters"}) {
        auto it = job.provenance.find(k);
        id += std::string(k) + ": " + (it == job.provenance.end() ? std::string("-") : it->second.str()) + "\n";
    }
    id += "integrator: " + job.integrator->name() + "\n";
    id += "spp: " + std::to_string(opts.spp) + " (" + std::to_string(opts.sppPerPass) + " per pass)\n";
    id += "seed: " + std::to_string(job.sampler->seed()) + "\n";
    if (job.film->varianceLayers()) id += "variance layers: yes\n";  // (absent in older checkpoints)
    return id;
}

namespace {
// The first line in which two identities differ, for the refusal message.
std::string FirstDifference(const std::string &a, const std::string &b) {
    std::istringstream sa(a), sb(b);
    std::string la, lb;
    while (true) {
        bool ga = bool(std::getline(sa, la)), gb = bool(std::getline(sb, lb));
        if (!ga && !gb) return "";
        if (!ga) la = "(none)";
        if (!gb) lb = "(none)";
        if (la != lb) return "checkpoint has \"" + la + "\", this render \"" + lb + "\"";
    }
}
}  // namespace

RenderResult RenderJobImage(RenderJob &job, const RenderOptions &opts) {
    using Clock = std::chrono::steady_clock;
    auto seconds = [](Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); };
    const double cpu0 = CpuSeconds();
    const auto t0 = Clock::now();
    job.integrator->preprocess(*job.scene, *job.film);
    const auto t1 = Clock::now();
    RenderOptions loopOpts = opts;
    if (opts.timeLimit > 0) {  // at least one pass runs whatever is left
        // The estimate may time a probe of its own: it is taken first, so that its
        // time counts as spent.
        const double finish = job.integrator->finishEstimate();
        loopOpts.timeLimit = std::max(1e-9, opts.timeLimit - seconds(t0, Clock::now()) - finish);
    }
    // Checkpoints: resume, --passes, periodic and final writes (job/checkpoint.h).
    const std::string identity = RenderIdentity(job, opts);
    Checkpoint prior;
    bool resumed = false;
    if (!opts.resumeFile.empty()) {
        if (opts.passBegin != 0 || opts.passEnd >= 0) throw Error("--resume and --passes exclude each other");
        prior = ReadCheckpoint(opts.resumeFile);
        if (prior.identity != identity || prior.integrator != job.integrator->name())
            throw Error(opts.resumeFile + ": a checkpoint of another render (" + FirstDifference(prior.identity, identity) +
                        "); resume with the scene, integrator, parameters, --spp and --seed it was made with");
        job.film->loadState(prior.film);
        try {
            job.integrator->loadState(prior.state);
        } catch (const Error &e) {
            throw Error(opts.resumeFile + ": " + e.what());
        }
        loopOpts.firstPass = prior.passEnd;
        loopOpts.firstSpp = prior.sppEnd;
        resumed = true;
    } else if (opts.passBegin != 0 || opts.passEnd >= 0) {
        if (opts.passBegin > 0 && !job.integrator->independentPasses())
            throw Error("--passes " + std::to_string(opts.passBegin) + ":...: " + job.integrator->name() +
                        "'s passes depend on the ones before (split it with --checkpoint and --resume instead)");
        if (opts.timeLimit > 0 && opts.spp <= 0) throw Error("--passes needs --spp (or the sampler's count), not --time alone");
        loopOpts.firstPass = opts.passBegin;
        loopOpts.firstSpp = -1;
        loopOpts.lastPass = opts.passEnd;
    }
    auto makeCheckpoint = [&](const RenderStats &st) {
        Checkpoint c;
        c.identity = identity;
        c.integrator = job.integrator->name();
        c.seed = job.sampler->seed();
        c.passBegin = resumed ? prior.passBegin : st.firstPass;
        c.sppBegin = resumed ? prior.sppBegin : st.firstSpp;
        c.passEnd = st.passes;
        c.sppEnd = st.spp;
        c.complete = st.complete;
        c.seconds = prior.seconds + seconds(t0, Clock::now());
        c.nonFinite = prior.nonFinite + st.nonFinite;
        c.film = job.film->saveState();
        c.state = job.integrator->saveState();
        return c;
    };
    auto lastWrite = Clock::now();
    double writeSeconds = 0;
    size_t writeBytes = 0;
    auto writeCheckpoint = [&](const RenderStats &st) {
        const auto w0 = Clock::now();
        Checkpoint c = makeCheckpoint(st);
        WriteCheckpoint(opts.checkpointFile, c);
        lastWrite = Clock::now();
        writeSeconds = seconds(w0, lastWrite);
        writeBytes = c.film.size() + c.state.size();
    };
    if (!opts.checkpointFile.empty()) {
        loopOpts.wholePasses = true;
        loopOpts.afterPass = [&](const RenderStats &st) {
            if (seconds(lastWrite, Clock::now()) >= opts.checkpointInterval) writeCheckpoint(st);
        };
    }
    RenderResult r;
    r.stats = RunRender(*job.integrator, *job.scene, *job.film, *job.sampler, loopOpts);
    if (!opts.checkpointFile.empty()) writeCheckpoint(r.stats);
    const auto t2 = Clock::now();
    r.image = job.film->toImage();
    job.integrator->finish(*job.film, r.stats, &r.image);
    const auto t3 = Clock::now();
    r.stats.seconds = seconds(t0, t3);

    const Film &film = *job.film;
    Metadata &m = r.image.metadata;
    for (const auto &kv : job.provenance) m[kv.first] = kv.second;
    m["integrator"] = job.integrator->name();
    m["spp"] = MetaValue::Int(r.stats.spp);
    m["passes"] = MetaValue::Int(r.stats.passes);
    m["seed"] = std::to_string(r.stats.seed);
    m["threads"] = MetaValue::Int(opts.nthreads > 0 ? opts.nthreads : int(std::thread::hardware_concurrency()));
    m["render_seconds"] = MetaValue::Double(r.stats.seconds);
    m["seconds_preprocess"] = MetaValue::Double(seconds(t0, t1));
    m["seconds_passes"] = MetaValue::Double(seconds(t1, t2));
    m["seconds_finish"] = MetaValue::Double(seconds(t2, t3));
    m["cpu_seconds"] = MetaValue::Double(CpuSeconds() - cpu0);
    m["stop_reason"] = r.stats.interrupted ? "interrupted" : r.stats.timeLimited ? "time budget" : "completed";
    if (opts.timeLimit > 0) m["time_budget"] = MetaValue::Double(opts.timeLimit);
    m["nonfinite_discarded"] = MetaValue::Int(int64_t(r.stats.nonFinite));
    m["output_values_clamped"] = MetaValue::Int(int64_t(film.clampedValues()));
    m["peak_rss_mb"] = MetaValue::Double(PeakRSSMegabytes());
    m["gradus_version"] = std::string(GradusVersion()) + " (" + GradusGitCommit() + ")";
    if (resumed) {
        m["resumed_from"] = opts.resumeFile;
        m["resumed_at_pass"] = MetaValue::Int(prior.passEnd);
        m["render_seconds_all_sessions"] = MetaValue::Double(prior.seconds + r.stats.seconds);
    }
    if (loopOpts.firstPass > 0 || loopOpts.lastPass >= 0) {
        m["pass_begin"] = MetaValue::Int(resumed ? prior.passBegin : r.stats.firstPass);
        m["pass_end"] = MetaValue::Int(r.stats.passes);
    }
    if (!opts.checkpointFile.empty()) {
        m["checkpoint"] = opts.checkpointFile;
        m["checkpoint_bytes"] = MetaValue::Int(int64_t(writeBytes));
        m["checkpoint_write_seconds"] = MetaValue::Double(writeSeconds);
    }
    // Crops keep their place in the full image (EXR data window in the display window).
    r.image.originX = film.pixelBounds().pMin.x;
    r.image.originY = film.pixelBounds().pMin.y;
    r.image.displayWidth = film.fullResolution().x;
    r.image.displayHeight = film.fullResolution().y;
    return r;
}

void ApplyParamOverrides(const std::vector<std::string> &overrides, EntityDesc *idesc) {
    if (overrides.empty()) return;
    const IntegratorInfo *info = nullptr;
    for (const auto &i : IntegratorRegistry())
        if (i.name == idesc->type) info = &i;
    if (!info) return;  // CreateIntegrator reports the unknown name
    const std::vector<ParamInfo> table = info->parameters();
    FileLoc loc;
    loc.file = std::make_shared<const std::string>("<command line --param>");
    for (const std::string &o : overrides) {
        size_t eq = o.find('=');
        std::string name = o.substr(0, eq);
        if (eq == std::string::npos || name.empty())
            throw Error(loc, "--param expects NAME=VALUE, got \"" + o + "\"");
        const ParamInfo *pi = nullptr;
        for (const auto &e : table)
            if (e.name == name) pi = &e;
        if (!pi)
            throw Error(loc, "integrator \"" + idesc->type + "\" has no parameter \"" + name +
                                 "\" (see gradus --describe " + idesc->type + ")");
        Param p;
        p.type = pi->typeName();
        p.name = name;
        p.loc = loc;
        std::string value = o.substr(eq + 1);
        if (p.type == "string") {
            p.strings.push_back(value);
        } else if (p.type == "bool") {
            if (value != "true" && value != "false")
                throw Error(loc, "--param " + name + " expects true or false, got \"" + value + "\"");
            p.bools.push_back(value == "true");
        } else {  // integer / float: one or more numbers separated by commas or spaces
            for (char &c : value)
                if (c == ',') c = ' ';
            std::istringstream in(value);
            std::string word;
            while (in >> word) {
                char *end = nullptr;
                double v = std::strtod(word.c_str(), &end);
                if (*end != 0 || !std::isfinite(v) || (p.type == "integer" && v != std::floor(v)))
                    throw Error(loc, "--param " + name + " expects " + p.type + " values, got \"" + word + "\"");
                p.numbers.push_back(v);
            }
            if (p.numbers.empty()) throw Error(loc, "--param " + name + " has no value");
        }
        idesc->params.add(std::move(p));
    }
}

}  // namespace gradus
