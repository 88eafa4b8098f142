// gradus._gradus: the C++ half of the Python module (python/gradus/ wraps it).
// Renders take the command line's route (job/render_route.h), so a render
// through Python equals gradus's at equal options bit for bit.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/error.h"
#include "core/provenance.h"
#include "core/stats.h"
#include "image/image.h"
#include "image/metrics.h"
#include "render/integrator.h"
#include "render/params.h"
#include "reconstruction/reconstruction.h"
#include "job/environment.h"
#include "job/render_route.h"
#include "render/display.h"
#include "integrators/registry.h"

namespace py = pybind11;
using namespace gradus;

namespace {

// A render's process-wide state (interrupt flag, statistics counters, the
// record of input files) admits one render or scene load at a time.
std::mutex gRenderMutex;

// Raises gradus.SceneError (file, line, column; None when unknown).
[[noreturn]] void RaiseSceneError(const std::string &msg, const std::string &file, int line, int column) {
    py::object type = py::module_::import("gradus._errors").attr("SceneError");
    py::object none = py::none();
    py::object exc = type(msg, file.empty() ? none : py::str(file), line > 0 ? py::int_(line) : none,
                          column > 0 ? py::int_(column) : none);
    PyErr_SetObject(type.ptr(), exc.ptr());
    throw py::error_already_set();
}

// A scene load's or render's error: located ones carry their place; others
// name `file` (the scene) when given.
[[noreturn]] void RaiseFromError(const Error &e, const std::string &file) {
    if (const FileLoc *loc = e.location()) RaiseSceneError(e.what(), loc->filename(), loc->line, loc->column);
    RaiseSceneError(e.what(), file, 0, 0);
}

// ---- images <-> numpy -------------------------------------------------------

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

// The channels of one layer in output order: R, G, B when present, else the
// layer's channels in file order.
std::vector<int> LayerChannels(const Image &img, const std::string &layer, std::vector<std::string> *names) {
    const auto &all = img.channelNames();
    std::vector<int> members;
    names->clear();
    for (size_t i = 0; i < all.size(); ++i) {
        size_t dot = all[i].rfind('.');
        std::string l = dot == std::string::npos ? "" : all[i].substr(0, dot);
        if (l != layer) continue;
        members.push_back(int(i));
        names->push_back(dot == std::string::npos ? all[i] : all[i].substr(dot + 1));
    }
    std::vector<int> rgb;
    for (const char *c : {"R", "G", "B"}) {
        auto it = std::find(names->begin(), names->end(), c);
        if (it != names->end()) rgb.push_back(members[size_t(it - names->begin())]);
    }
    if (rgb.size() == 3 && members.size() == 3) {
        *names = {"R", "G", "B"};
        return rgb;
    }
    return members;
}

py::dict MetadataToPython(const Metadata &m) {
    py::dict d;
    for (const auto &kv : m) {
        const MetaValue &v = kv.second;
        if (v.type() == MetaValue::Type::Int)
            d[py::str(kv.first)] = py::int_(std::stoll(v.str()));
        else if (v.type() == MetaValue::Type::Double)
            d[py::str(kv.first)] = py::float_(std::strtod(v.c_str(), nullptr));
        else
            d[py::str(kv.first)] = py::str(v.str());
    }
    return d;
}

Metadata MetadataFromPython(const py::dict &d) {
    Metadata m;
    for (auto kv : d) {
        std::string key = py::cast<std::string>(py::str(kv.first));
        py::handle v = kv.second;
        if (py::isinstance<py::bool_>(v))
            m[key] = MetaValue::Int(v.cast<bool>() ? 1 : 0);
        else if (py::isinstance<py::int_>(v))
            m[key] = MetaValue::Int(v.cast<int64_t>());
        else if (py::isinstance<py::float_>(v))
            m[key] = MetaValue::Double(v.cast<double>());
        else
            m[key] = py::cast<std::string>(py::str(v));
    }
    return m;
}

// {"layers": {name: H x W x C float32}, "channels": {name: [...]}, "metadata",
// "origin": (x, y), "display_size": (w, h)}; layer "" is the unprefixed one.
py::dict ImageToPython(const Image &img) {
    py::dict layers, channels;
    const int w = img.width(), h = img.height(), nc = img.numChannels();
    const float *src = img.data().data();
    for (const std::string &layer : img.layers()) {
        std::vector<std::string> names;
        std::vector<int> idx = LayerChannels(img, layer, &names);
        const size_t k = idx.size();
        FloatArray a({size_t(h), size_t(w), k});
        float *dst = a.mutable_data();
        for (size_t p = 0; p < size_t(w) * size_t(h); ++p)
            for (size_t c = 0; c < k; ++c) dst[p * k + c] = src[p * size_t(nc) + size_t(idx[c])];
        layers[py::str(layer)] = a;
        channels[py::str(layer)] = names;
    }
    py::dict d;
    d["layers"] = layers;
    d["channels"] = channels;
    d["metadata"] = MetadataToPython(img.metadata);
    d["origin"] = py::make_tuple(img.originX, img.originY);
    d["display_size"] = py::make_tuple(img.displayWidth > 0 ? img.displayWidth : w,
                                       img.displayHeight > 0 ? img.displayHeight : h);
    return d;
}

// An H x W x 3 (or H x W, H x W x 1: replicated) array as an RGB image.
Image ArrayToRGB(const FloatArray &a, const char *what) {
    if (a.ndim() != 2 && a.ndim() != 3) throw py::value_error(std::string(what) + ": expected an H x W x 3 array");
    const size_t h = size_t(a.shape(0)), w = size_t(a.shape(1)), k = a.ndim() == 3 ? size_t(a.shape(2)) : 1;
    if (k != 3 && k != 1) throw py::value_error(std::string(what) + ": expected 3 channels (or 1), got " + std::to_string(k));
    if (h == 0 || w == 0) throw py::value_error(std::string(what) + ": empty image");
    Image img = Image::RGB(int(w), int(h));
    const float *src = a.data();
    float *dst = img.data().data();
    for (size_t p = 0; p < w * h; ++p)
        for (size_t c = 0; c < 3; ++c) dst[p * 3 + c] = src[p * k + (k == 3 ? c : 0)];
    return img;
}

// ---- integrators --------------------------------------------------------------

const IntegratorInfo &FindIntegrator(const std::string &name) {
    std::string valid;
    for (const auto &info : IntegratorRegistry()) {
        if (info.name == name) return info;
        valid += (valid.empty() ? "" : ", ") + info.name;
    }
    throw py::value_error("unknown integrator \"" + name + "\" (available: " + valid + ")");
}

py::dict Integrators() {
    py::dict d;
    for (const auto &info : IntegratorRegistry()) d[py::str(info.name)] = info.description;
    return d;
}

py::dict Describe(const std::string &name) {
    const IntegratorInfo &info = FindIntegrator(name);
    const std::vector<ParamInfo> params = info.parameters();
    py::list list;
    for (const ParamInfo &p : params) {
        py::dict e;
        e["name"] = p.name;
        e["type"] = p.typeName();
        e["default"] = p.defaultText;
        e["help"] = p.help;
        e["values"] = p.values;
        e["group"] = p.group;
        list.append(e);
    }
    py::dict d;
    d["name"] = info.name;
    d["description"] = info.description;
    d["parameters"] = list;
    d["text"] = FormatParams(params);
    return d;
}

// ---- scenes and renders -----------------------------------------------------------

// A loaded scene: parsed and built once; renders share the built Scene
// (job/render_route.h: LoadedScene) unless they ask for other environment
// options, which build it anew (and keep that build).
struct PyScene {
    std::string path;
    std::shared_ptr<LoadedScene> loaded;  // guarded by gRenderMutex
    py::dict info;                        // from the build at load time
};

// The environment options of a load or a render (map "" = none given).
EnvironmentOptions Environment(const std::string &map, double scale, double rotate) {
    EnvironmentOptions e;
    e.map = map;
    e.scale = scale;
    e.rotateDegrees = rotate;
    return e;
}

// What a render hands back from its thread.
struct RenderOutput {
    Image image;
    RenderStats stats;
    std::map<std::string, uint64_t> counters;
    std::string statistics;
    std::vector<std::string> notes;
};

PyScene LoadPyScene(const std::string &path, std::optional<std::pair<int, int>> resolution,
                  std::optional<std::vector<double>> crop, const std::string &camera, bool quick,
                  const std::string &envmap, double envmapScale, double envmapRotate) {
    PyScene s;
    s.path = path;
    GltfOptions gltf;
    gltf.camera = camera;
    BuildOptions build;
    build.quiet = true;
    build.checkOutput = false;  // the module writes no file
    build.quick = quick;
    if (resolution) build.resolution = {resolution->first, resolution->second};
    if (crop) {
        build.hasCrop = true;
        for (int i = 0; i < 4; ++i) build.crop[i] = Float((*crop)[size_t(i)]);
    }
    build.environment = Environment(envmap, envmapScale, envmapRotate);
    if (!camera.empty() && !IsGltfFile(path))
        throw py::value_error("camera applies to glTF scenes (.gltf, .glb); pbrt scenes place glTF cameras with GltfAsset");
    // Parsed and built once: the scene's errors are raised here, and renders use the build.
    RenderJob job;
    try {
        py::gil_scoped_release nogil;
        std::lock_guard<std::mutex> lock(gRenderMutex);
        LoadEnvironmentMap(&build.environment);  // before the scene, as gradus does
        s.loaded = gradus::LoadScene(path, gltf, build, &job);
    } catch (const Error &e) {
        RaiseFromError(e, path);
    }
    const double seconds = s.loaded->seconds;
    const Point2i full = job.film->fullResolution();
    const Bounds2i &pb = job.film->pixelBounds();
    s.info["resolution"] = py::make_tuple(full.x, full.y);
    s.info["pixel_bounds"] = py::make_tuple(pb.pMin.x, pb.pMin.y, pb.pMax.x, pb.pMax.y);
    s.info["integrator"] = job.integrator->name();
    s.info["spp"] = job.sampler->samplesPerPixel();
    s.info["features"] = job.scene->features.describe();
    s.info["notes"] = job.warnings;
    s.info["provenance"] = MetadataToPython(job.provenance);
    s.info["load_seconds"] = seconds;
    return s;
}

py::dict StatsToPython(const RenderOutput &out) {
    const RenderStats &st = out.stats;
    py::dict d;
    d["spp"] = st.spp;
    d["passes"] = st.passes;
    d["camera_samples"] = st.cameraSamples;
    d["seconds"] = st.seconds;
    d["seed"] = st.seed;
    d["nonfinite_discarded"] = st.nonFinite;
    d["interrupted"] = st.interrupted;
    d["time_limited"] = st.timeLimited;
    d["complete"] = st.complete;
    d["counters"] = out.counters;
    d["text"] = out.statistics;
    d["notes"] = out.notes;
    return d;
}

// What the render thread and the watching Python thread share.
struct RenderWatch {
    std::mutex m;
    std::condition_variable cv;
    bool done = false;
    std::atomic<int> sppDone{0}, sppTotal{-1};
    std::exception_ptr failure;
    RenderOutput out;
};

// The render thread: builds the job on the kept scene (or loads and builds
// the scene anew when bo's environment differs from its, keeping that one)
// and renders into w.out (or sets w.failure), then w.done.
void RenderThread(PyScene &s, BuildOptions &bo, RenderOptions &ro, const std::string &commandLine, RenderWatch &w) {
    try {
        double loadSeconds = 0;
        RenderJob job;
        if (s.loaded->sharesWith(bo)) {
            bo.environment.image = s.loaded->build.environment.image;
            job = BuildLoadedJob(*s.loaded, bo, &loadSeconds);
        } else {
            LoadEnvironmentMap(&bo.environment);
            s.loaded = gradus::LoadScene(s.path, s.loaded->gltf, bo, &job);
            loadSeconds = s.loaded->seconds;
        }
        ResolveSampleCount(job, bo, &ro);
        w.sppTotal = ro.spp;
        RenderResult r = RenderLoadedJob(job, ro, s.path, commandLine, loadSeconds);
        w.out.image = std::move(r.image);
        w.out.stats = r.stats;
        w.out.counters = StatRegistry::get().snapshot();
        w.out.statistics = FormatStats(w.out.counters) + job.integrator->statistics();
        w.out.notes = job.warnings;
    } catch (...) {
        w.failure = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(w.m);
    w.done = true;
    w.cv.notify_all();
}

double SecondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Until the render thread is done: every 50 ms (GIL released while waiting)
// checks for Ctrl-C and calls `progress` on new samples. The first Python
// exception is kept in *pyError and interrupts the render.
void WatchRender(RenderWatch &w, const py::object &progress, std::chrono::steady_clock::time_point t0,
                 int *reported, std::optional<py::error_already_set> *pyError) {
    auto stop = [&](py::error_already_set &&e) {
        if (!*pyError) pyError->emplace(std::move(e));
        RequestInterrupt();
    };
    while (true) {
        bool finished;
        {
            py::gil_scoped_release nogil;
            std::unique_lock<std::mutex> lock(w.m);
            finished = w.cv.wait_for(lock, std::chrono::milliseconds(50), [&] { return w.done; });
        }
        if (finished) break;
        if (*pyError) continue;
        if (PyErr_CheckSignals() != 0) {
            stop(py::error_already_set());
            continue;
        }
        const int now = w.sppDone;
        if (!progress.is_none() && now != *reported && w.sppTotal >= 0) {
            *reported = now;
            try {
                progress(now, int(w.sppTotal), SecondsSince(t0));
            } catch (py::error_already_set &e) {
                stop(std::move(e));
            }
        }
    }
}

// Renders on a thread of its own while this (Python) thread, with the GIL
// released between polls, watches for Ctrl-C (PyErr_CheckSignals) and calls
// `progress`. A Python exception there (KeyboardInterrupt, or one raised by
// `progress`) stops the render as gradus's first SIGINT does; it is raised
// once the render loop has stopped.
py::dict Render(PyScene &s, const std::string &integrator, long long spp, double time, long long seed,
                int threads, const std::vector<std::string> &params, py::object progress,
                const std::string &commandLine, const std::string &envmap, double envmapScale, double envmapRotate,
                const std::string &displayServer, bool displayLayers) {
    if (!displayServer.empty()) {
        try {
            ParseDisplayAddress(displayServer);  // before anything is rendered
        } catch (const Error &e) {
            throw py::value_error(e.what());
        }
    }
    BuildOptions bo;
    RenderOptions ro;
    {
        py::gil_scoped_release nogil;
        std::lock_guard<std::mutex> lock(gRenderMutex);
        bo = s.loaded->build;
    }
    bo.environment = Environment(envmap, envmapScale, envmapRotate);
    bo.integratorOverride = integrator;
    bo.sppOverride = int(spp);
    bo.seed = uint64_t(seed);
    bo.paramOverrides = params;
    ro.nthreads = threads;
    ro.timeLimit = time;
    ro.quiet = true;
    ro.displayServer = displayServer;
    ro.displayLayers = displayLayers;
    RenderWatch w;
    ro.afterPass = [&w](const RenderStats &st) { w.sppDone = st.spp; };

    const auto t0 = std::chrono::steady_clock::now();
    std::unique_lock<std::mutex> renderLock(gRenderMutex, std::defer_lock);
    {
        py::gil_scoped_release nogil;
        renderLock.lock();
    }
    ResetInterrupt();
    std::thread worker([&] { RenderThread(s, bo, ro, commandLine, w); });
    std::optional<py::error_already_set> pyError;
    int reported = -1;
    try {
        WatchRender(w, progress, t0, &reported, &pyError);
    } catch (...) {  // never leave the thread running
        RequestInterrupt();
        py::gil_scoped_release nogil;
        worker.join();
        ResetInterrupt();
        throw;
    }
    {
        py::gil_scoped_release nogil;
        worker.join();
    }
    renderLock.unlock();
    ResetInterrupt();
    if (pyError) throw std::move(*pyError);
    if (w.failure) {
        try {
            std::rethrow_exception(w.failure);
        } catch (const Error &e) {
            RaiseFromError(e, s.path);
        }
    }
    if (!progress.is_none() && w.out.stats.spp != reported) progress(w.out.stats.spp, int(w.sppTotal), SecondsSince(t0));
    py::dict d = ImageToPython(w.out.image);
    d["stats"] = StatsToPython(w.out);
    return d;
}

// ---- reconstruction, metrics, image files --------------------------------------------

std::vector<float> Interleaved(const FloatArray &a, const char *what, int *w, int *h) {
    if (a.ndim() != 3 || a.shape(2) != 3) throw py::value_error(std::string(what) + ": expected an H x W x 3 array");
    if (*w < 0) {
        *h = int(a.shape(0));
        *w = int(a.shape(1));
    } else if (a.shape(0) != *h || a.shape(1) != *w) {
        throw py::value_error(std::string(what) + ": size differs from the primal's");
    }
    return std::vector<float>(a.data(), a.data() + a.size());
}

py::object ReconstructArrays(const FloatArray &primal, const FloatArray &dx, const FloatArray &dy, const std::string &method,
                       std::optional<double> alpha, std::optional<FloatArray> primalVar, std::optional<FloatArray> dxVar,
                       std::optional<FloatArray> dyVar, std::optional<FloatArray> separated, bool returnStats) {
    GradientImages in;
    int w = -1, h = -1;
    in.primal = Interleaved(primal, "primal", &w, &h);
    in.dx = Interleaved(dx, "dx", &w, &h);
    in.dy = Interleaved(dy, "dy", &w, &h);
    in.width = w;
    in.height = h;
    const int nv = int(bool(primalVar)) + int(bool(dxVar)) + int(bool(dyVar));
    if (nv != 0 && nv != 3) throw py::value_error("give all of primal_var, dx_var and dy_var, or none");
    if (nv == 3) {
        in.primalVar = Interleaved(*primalVar, "primal_var", &w, &h);
        in.dxVar = Interleaved(*dxVar, "dx_var", &w, &h);
        in.dyVar = Interleaved(*dyVar, "dy_var", &w, &h);
    }
    if (separated) in.separated = Interleaved(*separated, "separated", &w, &h);
    ReconstructionOptions o;
    try {
        o = ReconstructionOptions::Preset(method);
    } catch (const Error &e) {
        throw py::value_error(e.what());
    }
    if (alpha) o.alpha = *alpha;
    ReconstructionResult r;
    {
        py::gil_scoped_release nogil;
        r = Reconstruct(in, o);
    }
    FloatArray out({size_t(h), size_t(w), size_t(3)});
    std::copy(r.image.begin(), r.image.end(), out.mutable_data());
    if (!returnStats) return std::move(out);
    const ReconstructionStats &st = r.stats;
    py::dict d;
    d["method"] = st.method;
    d["norm"] = ReconstructionNormName(o.norm);
    d["alpha"] = o.alpha;
    d["seconds"] = st.seconds;
    d["irls_iterations"] = st.irlsIterations;
    d["cg_iterations"] = st.cgIterations;
    d["objective"] = st.objective;
    d["final_relative_residual"] = st.finalRelativeResidual;
    return py::make_tuple(out, d);
}

py::dict Metrics(const FloatArray &test, const FloatArray &ref, double discardFraction, long long discardCount,
                 double relEpsilon) {
    Image a = ArrayToRGB(test, "test"), b = ArrayToRGB(ref, "ref");
    CompareOptions o;
    o.discardFraction = discardFraction;
    o.discardCount = discardCount;
    o.relEpsilon = relEpsilon;
    ImageMetrics m;
    {
        py::gil_scoped_release nogil;
        m = CompareImages(a, b, o);
    }
    py::dict d;
    d["relmse"] = m.relmse;
    d["mse"] = m.mse;
    d["rmse"] = m.rmse;
    d["psnr"] = m.psnr;
    d["mean_test"] = m.meanImg;
    d["mean_ref"] = m.meanRef;
    d["mean_diff"] = m.meanDiff;
    d["mean_rel_diff"] = m.meanRelDiff;
    d["pixels"] = m.pixels;
    d["used_pixels"] = m.usedPixels;
    d["discarded_pixels"] = m.discardedPixels;
    d["nonfinite_pixels"] = m.nonFinitePixels;
    return d;
}

py::dict ReadImageFile(const std::string &path) {
    Image img;
    {
        py::gil_scoped_release nogil;
        img = ReadImage(path);
    }
    return ImageToPython(img);
}

// layers: {name: H x W x 3 (R, G, B) or H x W / H x W x 1 (Y)}; all of one size.
void WriteImageFile(const std::string &path, const py::dict &layers, const py::dict &metadata,
                    std::pair<int, int> origin, std::optional<std::pair<int, int>> displaySize) {
    if (layers.empty()) throw py::value_error("write_image: no layers");
    std::vector<std::pair<std::string, FloatArray>> in;
    for (auto kv : layers) in.emplace_back(py::cast<std::string>(kv.first), py::cast<FloatArray>(kv.second));
    const FloatArray &first = in.front().second;
    if (first.ndim() < 2) throw py::value_error("write_image: layers must be H x W x 3 or H x W arrays");
    const int h = int(first.shape(0)), w = int(first.shape(1));
    std::vector<std::string> names;
    std::vector<int> width;  // channels per layer
    for (const auto &l : in) {
        const FloatArray &a = l.second;
        const int k = a.ndim() == 3 ? int(a.shape(2)) : a.ndim() == 2 ? 1 : -1;
        if ((k != 1 && k != 3) || a.shape(0) != h || a.shape(1) != w)
            throw py::value_error("write_image: layer \"" + l.first + "\" must be " + std::to_string(h) + " x " +
                                  std::to_string(w) + " x 3 (or x 1)");
        for (const char *c : k == 3 ? std::vector<const char *>{"R", "G", "B"} : std::vector<const char *>{"Y"})
            names.push_back(l.first.empty() ? std::string(c) : l.first + "." + c);
        width.push_back(k);
    }
    Image img(w, h, names);
    float *dst = img.data().data();
    const size_t nc = names.size();
    size_t offset = 0;
    for (size_t i = 0; i < in.size(); ++i) {
        const float *src = in[i].second.data();
        const size_t k = size_t(width[i]);
        for (size_t p = 0; p < size_t(w) * size_t(h); ++p)
            for (size_t c = 0; c < k; ++c) dst[p * nc + offset + c] = src[p * k + c];
        offset += k;
    }
    img.metadata = MetadataFromPython(metadata);
    img.originX = origin.first;
    img.originY = origin.second;
    if (displaySize) {
        img.displayWidth = displaySize->first;
        img.displayHeight = displaySize->second;
    }
    py::gil_scoped_release nogil;
    WriteImage(path, img);
}

}  // namespace

PYBIND11_MODULE(_gradus, m) {
    m.doc() = "Gradus renderer (C++ core; use the gradus package)";
    // Errors of the image and reconstruction code: gradus.Error.
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const Error &e) {
            py::object type = py::module_::import("gradus._errors").attr("Error");
            PyErr_SetString(type.ptr(), e.what());
        }
    });
    m.def("version", [] { return std::string(GradusVersion()) + " (" + GradusGitCommit() + ")"; });
    m.def("integrators", &Integrators);
    m.def("describe", &Describe, py::arg("name"));
    py::class_<PyScene>(m, "Scene")
        .def_readonly("path", &PyScene::path)
        .def_readonly("info", &PyScene::info)
        .def("render", &Render, py::arg("integrator"), py::arg("spp"), py::arg("time"), py::arg("seed"),
             py::arg("threads"), py::arg("params"), py::arg("progress"), py::arg("command_line"), py::arg("envmap"),
             py::arg("envmap_scale"), py::arg("envmap_rotate"), py::arg("display_server"), py::arg("display_layers"));
    m.def("load_scene", &LoadPyScene, py::arg("path"), py::arg("resolution"), py::arg("crop"), py::arg("camera"),
          py::arg("quick"), py::arg("envmap"), py::arg("envmap_scale"), py::arg("envmap_rotate"));
    m.def("reconstruct", &ReconstructArrays, py::arg("primal"), py::arg("dx"), py::arg("dy"), py::arg("method"),
          py::arg("alpha"), py::arg("primal_var"), py::arg("dx_var"), py::arg("dy_var"), py::arg("separated"), py::arg("return_stats"));
    m.def("metrics", &Metrics, py::arg("test"), py::arg("ref"), py::arg("discard_fraction"),
          py::arg("discard_count"), py::arg("rel_epsilon"));
    m.def("read_image", &ReadImageFile, py::arg("path"));
    m.def("write_image", &WriteImageFile, py::arg("path"), py::arg("layers"), py::arg("metadata"),
          py::arg("origin"), py::arg("display_size"));
}
