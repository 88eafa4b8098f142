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
#include "render/display.h"

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
constexpr const char *kMediaIntegrators =
    "path (pbrt-v3's volpath), bdpt, mbdpt, vcm (modes vcm and vc), mlt, gpt and gbdpt";
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
        // Without an Integrator directive (--integrator on a scene without one) the material's place.
        throw Error(idesc.present ? idesc.loc : mloc, "Integrator \"" + idesc.type +
                                                        "\" does not render subsurface scattering (material made at " +
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

// 1. The film: resolution (scene, --resolution, --quick), crop window, output
// file (checked writable before any geometry is loaded), pixel filter.
std::unique_ptr<Film> CreateJobFilm(const SceneDesc &desc, const BuildOptions &opts, Point2i *resOut,
                                    Float crop[4]) {
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
    *resOut = res;
    try {
        return std::make_unique<Film>(res, crop, std::move(filter), filename, scale);
    } catch (const Error &e) {  // a film too large for this machine: located at the resolution
        throw Error(fp.locOf("xresolution", fd.loc), e.what());
    }
}

// 3. The integrator: --integrator and --param overrides, pbrt-v3's sppm and
// volpath names, unused parameters (warnings when overridden, else errors),
// variance layers, an integrator's own sample count, "pixelbounds".
void CreateJobIntegrator(const SceneDesc &desc, const BuildOptions &opts, RenderJob *jobOut, EntityDesc *idescOut) {
    RenderJob &job = *jobOut;
    EntityDesc &idesc = *idescOut;
    idesc = desc.integrator;
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
    if (const int n = job.integrator->defaultSamplesPerPixel(); n > 0 && opts.sppOverride <= 0) {
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
}

// 5. Provenance: the resolved parameters of every entity and the input files.
void RecordJobProvenance(const SceneDesc &desc, const BuildOptions &opts, const EntityDesc &sdesc,
                         const EntityDesc &idesc, Point2i res, const Float crop[4], const InputFilesSummary &in,
                         RenderJob *job) {
    const EntityDesc &fd = desc.film;
    Metadata &m = job->provenance;
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
    m["variance_layers"] = MetaValue::Int(job->film->varianceLayers() ? 1 : 0);
    if (opts.environment.given()) {
        m["environment"] = opts.environment.describe();
        job->environmentIdentity = opts.environment.identity();
    }
    m["scene_files"] = MetaValue::Int(in.files);
    m["scene_bytes"] = MetaValue::Int(int64_t(in.bytes));
    m["scene_hash"] = "fnv1a64:" + in.hash;
}

}  // namespace

RenderJob BuildRenderJob(const SceneDesc &desc, const BuildOptions &opts, std::shared_ptr<Scene> scene,
                         const InputFilesSummary *inputs) {
    RenderJob job;
    job.warnings = desc.notes;
    Point2i res;
    Float crop[4] = {0, 1, 0, 1};
    job.film = CreateJobFilm(desc, opts, &res, crop);
    // 2. The sampler (--spp, --quick: 1/8 of the samples).
    EntityDesc sdesc = desc.sampler;
    if (!sdesc.present) sdesc.type = "halton";
    job.sampler = CreateSampler(sdesc, opts.seed, opts.sppOverride);
    if (opts.quick && opts.sppOverride <= 0)
        job.sampler = CreateSampler(sdesc, opts.seed, std::max(1, job.sampler->samplesPerPixel() / 8));
    sdesc.params.checkUnused("Sampler \"" + sdesc.type + "\"");
    if (desc.accelerator.present) {
        // Embree replaces pbrt-v3's BVH/kd-tree; their tuning parameters are accepted and ignored.
        for (const auto &p : desc.accelerator.params.all()) p.used = true;
    }
    EntityDesc idesc;
    CreateJobIntegrator(desc, opts, &job, &idesc);
    // 4. The scene, and the scene parts this integrator refuses.
    job.scene = scene ? std::move(scene) : std::shared_ptr<Scene>(BuildScene(desc, res));
    job.warnings.insert(job.warnings.end(), job.scene->notes.begin(), job.scene->notes.end());
    RefuseUnhandledParts(*job.integrator, *job.scene, desc, idesc);
    RecordJobProvenance(desc, opts, sdesc, idesc, res, crop, inputs ? *inputs : InputFiles(), &job);
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
    // --envmap (likewise absent without it): the map's contents are in scene_hash, not its path.
    if (job.environmentIdentity.size()) id += "environment: " + job.environmentIdentity + "\n";
    return id;
}

namespace {

using Clock = std::chrono::steady_clock;
double SecondsBetween(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

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

// A render's checkpoints (job/checkpoint.h): --resume and --passes set where
// the loop starts and stops; --checkpoint writes after passes and at the end.
class CheckpointSession {
  public:
    CheckpointSession(RenderJob &job, const RenderOptions &opts, Clock::time_point t0)
        : job_(job), opts_(opts), t0_(t0), identity_(RenderIdentity(job, opts)), lastWrite_(Clock::now()) {}
    // Reads a resumed render's state or applies --passes to the loop's options.
    void begin(RenderOptions *loopOpts);
    // Periodic writes (whole passes only) when --checkpoint is given.
    void installWriter(RenderOptions *loopOpts) {
        if (opts_.checkpointFile.empty()) return;
        loopOpts->wholePasses = true;
        loopOpts->afterPass = [this](const RenderStats &st) {
            if (SecondsBetween(lastWrite_, Clock::now()) >= opts_.checkpointInterval) write(st);
        };
    }
    void writeFinal(const RenderStats &st) {
        if (!opts_.checkpointFile.empty()) write(st);
    }
    void record(const RenderOptions &loopOpts, const RenderStats &stats, Metadata *m) const;

  private:
    Checkpoint make(const RenderStats &st) const;
    void write(const RenderStats &st) {
        const auto w0 = Clock::now();
        Checkpoint c = make(st);
        WriteCheckpoint(opts_.checkpointFile, c);
        lastWrite_ = Clock::now();
        writeSeconds_ = SecondsBetween(w0, lastWrite_);
        writeBytes_ = c.film.size() + c.state.size();
    }
    RenderJob &job_;
    const RenderOptions &opts_;
    Clock::time_point t0_;
    std::string identity_;
    Checkpoint prior_;
    bool resumed_ = false;
    Clock::time_point lastWrite_;
    double writeSeconds_ = 0;
    size_t writeBytes_ = 0;
};

void CheckpointSession::begin(RenderOptions *loopOpts) {
    if (!opts_.resumeFile.empty()) {
        if (opts_.passBegin != 0 || opts_.passEnd >= 0) throw Error("--resume and --passes exclude each other");
        prior_ = ReadCheckpoint(opts_.resumeFile);
        if (prior_.identity != identity_ || prior_.integrator != job_.integrator->name())
            throw Error(opts_.resumeFile + ": a checkpoint of another render (" +
                        FirstDifference(prior_.identity, identity_) +
                        "); resume with the scene, integrator, parameters, --spp and --seed it was made with");
        job_.film->loadState(prior_.film);
        try {
            job_.integrator->loadState(prior_.state);
        } catch (const Error &e) {
            throw Error(opts_.resumeFile + ": " + e.what());
        }
        loopOpts->firstPass = prior_.passEnd;
        loopOpts->firstSpp = prior_.sppEnd;
        resumed_ = true;
    } else if (opts_.passBegin != 0 || opts_.passEnd >= 0) {
        if (opts_.passBegin > 0 && !job_.integrator->independentPasses())
            throw Error("--passes " + std::to_string(opts_.passBegin) + ":...: " + job_.integrator->name() +
                        "'s passes depend on the ones before (split it with --checkpoint and --resume instead)");
        if (opts_.timeLimit > 0 && opts_.spp <= 0)
            throw Error("--passes needs --spp (or the sampler's count), not --time alone");
        loopOpts->firstPass = opts_.passBegin;
        loopOpts->firstSpp = -1;
        loopOpts->lastPass = opts_.passEnd;
    }
}

Checkpoint CheckpointSession::make(const RenderStats &st) const {
    Checkpoint c;
    c.identity = identity_;
    c.integrator = job_.integrator->name();
    c.seed = job_.sampler->seed();
    c.passBegin = resumed_ ? prior_.passBegin : st.firstPass;
    c.sppBegin = resumed_ ? prior_.sppBegin : st.firstSpp;
    c.passEnd = st.passes;
    c.sppEnd = st.spp;
    c.complete = st.complete;
    c.seconds = prior_.seconds + SecondsBetween(t0_, Clock::now());
    c.nonFinite = prior_.nonFinite + st.nonFinite;
    c.film = job_.film->saveState();
    c.state = job_.integrator->saveState();
    return c;
}

void CheckpointSession::record(const RenderOptions &loopOpts, const RenderStats &stats, Metadata *mp) const {
    Metadata &m = *mp;
    if (resumed_) {
        m["resumed_from"] = opts_.resumeFile;
        m["resumed_at_pass"] = MetaValue::Int(prior_.passEnd);
        m["render_seconds_all_sessions"] = MetaValue::Double(prior_.seconds + stats.seconds);
    }
    if (loopOpts.firstPass > 0 || loopOpts.lastPass >= 0) {
        m["pass_begin"] = MetaValue::Int(resumed_ ? prior_.passBegin : stats.firstPass);
        m["pass_end"] = MetaValue::Int(stats.passes);
    }
    if (!opts_.checkpointFile.empty()) {
        m["checkpoint"] = opts_.checkpointFile;
        m["checkpoint_bytes"] = MetaValue::Int(int64_t(writeBytes_));
        m["checkpoint_write_seconds"] = MetaValue::Double(writeSeconds_);
    }
}

// The render's figures as typed metadata (RenderResult in job.h).
void RecordRenderFigures(const RenderJob &job, const RenderOptions &opts, const RenderStats &stats,
                         const Clock::time_point t[4], double cpuSeconds, double cpuPasses, Metadata *mp) {
    const Film &film = *job.film;
    Metadata &m = *mp;
    for (const auto &kv : job.provenance) m[kv.first] = kv.second;
    m["integrator"] = job.integrator->name();
    m["spp"] = MetaValue::Int(stats.spp);
    m["passes"] = MetaValue::Int(stats.passes);
    m["seed"] = std::to_string(stats.seed);
    m["threads"] = MetaValue::Int(opts.nthreads > 0 ? opts.nthreads : int(std::thread::hardware_concurrency()));
    m["render_seconds"] = MetaValue::Double(stats.seconds);
    m["seconds_preprocess"] = MetaValue::Double(SecondsBetween(t[0], t[1]));
    m["seconds_passes"] = MetaValue::Double(SecondsBetween(t[1], t[2]));
    m["seconds_finish"] = MetaValue::Double(SecondsBetween(t[2], t[3]));
    m["cpu_seconds"] = MetaValue::Double(cpuSeconds);
    m["cpu_seconds_passes"] = MetaValue::Double(cpuPasses);
    m["seconds_parallel"] = MetaValue::Double(stats.parallelSeconds);
    m["lane_occupancy"] = MetaValue::Double(stats.laneSeconds > 0 ? stats.busySeconds / stats.laneSeconds : 0);
    m["stop_reason"] = stats.interrupted ? "interrupted" : stats.timeLimited ? "time budget" : "completed";
    if (opts.timeLimit > 0) m["time_budget"] = MetaValue::Double(opts.timeLimit);
    m["nonfinite_discarded"] = MetaValue::Int(int64_t(stats.nonFinite));
    m["output_values_clamped"] = MetaValue::Int(int64_t(film.clampedValues()));
    m["peak_rss_mb"] = MetaValue::Double(PeakRSSMegabytes());
    m["gradus_version"] = std::string(GradusVersion()) + " (" + GradusGitCommit() + ")";
}

}  // namespace

RenderResult RenderJobImage(RenderJob &job, const RenderOptions &opts) {
    const double cpu0 = CpuSeconds();
    Clock::time_point t[4];
    t[0] = Clock::now();
    job.integrator->preprocess(*job.scene, *job.film);
    t[1] = Clock::now();
    RenderOptions loopOpts = opts;
    if (opts.timeLimit > 0) {  // at least one pass runs whatever is left
        // The estimate may time a probe of its own: it is taken first, so that its
        // time counts as spent.
        const double finish = job.integrator->finishEstimate();
        loopOpts.timeLimit = std::max(1e-9, opts.timeLimit - SecondsBetween(t[0], Clock::now()) - finish);
    }
    CheckpointSession checkpoints(job, opts, t[0]);
    checkpoints.begin(&loopOpts);
    checkpoints.installWriter(&loopOpts);
    // The live display starts with the film as the loop finds it (a resumed one is not black).
    std::unique_ptr<FilmDisplay> display;
    if (!opts.displayServer.empty() && !opts.debug) {
        const std::string &f = job.film->filename();
        try {  // (gradus checked the address before loading: this fails only if its name stopped resolving)
            display = std::make_unique<FilmDisplay>(ParseDisplayAddress(opts.displayServer), *job.film,
                                                    f.substr(f.find_last_of('/') + 1), opts.displayLayers, opts.quiet);
        } catch (const Error &e) {
            std::fprintf(stderr, "gradus: warning: %s; the render goes on without a display\n", e.what());
        }
    }
    RenderResult r;
    const double cpuLoop = CpuSeconds();
    r.stats = RunRender(*job.integrator, *job.scene, *job.film, *job.sampler, loopOpts);
    const double cpuPasses = CpuSeconds() - cpuLoop;
    checkpoints.writeFinal(r.stats);
    t[2] = Clock::now();
    r.image = job.film->toImage();
    job.integrator->finish(*job.film, r.stats, &r.image);
    t[3] = Clock::now();
    r.stats.seconds = SecondsBetween(t[0], t[3]);
    RecordRenderFigures(job, opts, r.stats, t, CpuSeconds() - cpu0, cpuPasses, &r.image.metadata);
    checkpoints.record(loopOpts, r.stats, &r.image.metadata);
    // Crops keep their place in the full image (EXR data window in the display window).
    const Film &film = *job.film;
    r.image.originX = film.pixelBounds().pMin.x;
    r.image.originY = film.pixelBounds().pMin.y;
    r.image.displayWidth = film.fullResolution().x;
    r.image.displayHeight = film.fullResolution().y;
    if (display) display->finish(r.image);  // the final image (after finish: e.g. a reconstruction)
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
