// Media rows of the conformance table (issue 56). Per media scene, every
// registered integrator (and vcm's modes vc and vm) either
//  - refuses the scene: exit 1 and an error located at the scene's Integrator
//    directive (file:line:column) naming the integrator and a medium of the
//    scene; or
//  - renders it, and then agrees in expectation with path and bdpt by
//    agreement.h's Welch tests, with a power check (X's runs scaled by
//    `power` and 1 / `power` must be rejected): 5% in the default tier, 2% in
//    the slow tier (conformance_slow_test.cpp).
// path and bdpt are compared with each other; every other row with their
// common expectation: Welch's t of X's mean against the average of path's and
// bdpt's means (WelchContrast: variance var(X) + (var(path) + var(bdpt)) / 4,
// Welch-Satterthwaite degrees of freedom over the three groups). Given that
// path and bdpt agree (their own row), this is agreement with both, at the
// table's full alpha and with a reference half as noisy as either alone.
// The scenes (data/media-*.pbrt, 24x24, box filter, maxdepth 5): homogeneous
// fog with a smoke sphere inside (media-fog), the same with the fog a density
// grid (media-grid), and a vacuum room holding a milk-filled glass sphere and
// a material-less box of smoke (media-interface).
// False positives: alpha = 1e-4 per (integrator, scene), split over the
// compared layers and agreement.h's pixel sets. path and bdpt are rendered
// once per scene and shared by every row, so one test covers a scene.
#pragma once
#include <chrono>
#include <fstream>
#include <regex>
#include <set>

#include "agreement.h"

namespace gradus::conformance {

inline const std::vector<std::string> &MediaScenes() {
    static const std::vector<std::string> names = {"media-fog", "media-grid", "media-interface"};
    return names;
}

// A row: an integrator, perhaps with parameters (vcm's modes).
struct MediaRow {
    std::string integrator;
    std::vector<std::string> extra;  // gradus arguments
    std::string label() const {
        std::string s = integrator;
        for (size_t i = 1; i < extra.size(); i += 2) s += " " + extra[i];
        return s;
    }
};

// Every registered integrator, and vcm's modes vc (renders media) and vm (refuses).
inline std::vector<MediaRow> MediaRows() {
    std::vector<MediaRow> rows;
    for (const std::string &x : Integrators()) {
        rows.push_back({x, {}});
        if (x == "vcm") {
            rows.push_back({x, {"--param", "mode=vc"}});
            rows.push_back({x, {"--param", "mode=vm"}});
        }
    }
    return rows;
}

// Rows documented to render media (README): refusing is a regression here.
inline bool MustRenderMedia(const MediaRow &r) {
    static const std::set<std::string> renders = {"path", "bdpt", "mbdpt", "vcm", "vcm mode=vc", "mlt", "gpt", "gbdpt"};
    return renders.count(r.label()) > 0;
}

// The scene's Integrator directive ("file:line:column") and its media names.
struct SceneFacts {
    std::string integratorAt;
    std::vector<std::string> media;
};
inline SceneFacts ReadSceneFacts(const std::string &scene) {
    SceneFacts f;
    std::ifstream in(ScenePath(scene));
    std::string line;
    const std::regex medium("^\\s*MakeNamedMedium\\s+\"([^\"]+)\"");
    for (int n = 1; std::getline(in, line); ++n) {
        std::smatch m;
        if (std::regex_search(line, m, medium)) f.media.push_back(m[1]);
        const size_t col = line.find_first_not_of(" \t");
        if (f.integratorAt.empty() && col != std::string::npos && line.compare(col, 11, "Integrator ") == 0)
            f.integratorAt = scene + ".pbrt:" + std::to_string(n) + ":" + std::to_string(col + 1) + ":";
    }
    return f;
}

// A refusal: exit 1, the error located at the Integrator directive, naming
// the integrator and one of the scene's media.
inline void CheckRefusal(const MediaRow &row, const std::string &scene, const ProcResult &r) {
    const SceneFacts facts = ReadSceneFacts(scene);
    ASSERT_FALSE(facts.integratorAt.empty()) << scene << " has no Integrator directive";
    EXPECT_TRUE(r.exited && r.exitCode == 1) << row.label() << " " << scene << ": " << r.describe();
    EXPECT_NE(r.err.find(facts.integratorAt), std::string::npos)
        << row.label() << " refuses " << scene << " without the location " << facts.integratorAt << ": " << r.err;
    EXPECT_NE(r.err.find("Integrator \"" + row.integrator + "\""), std::string::npos)
        << row.label() << ": the error does not name the integrator: " << r.err;
    bool named = false;
    for (const auto &m : facts.media) named = named || r.err.find("\"" + m + "\"") != std::string::npos;
    EXPECT_TRUE(named) << row.label() << ": the error names none of the scene's media: " << r.err;
}

struct MediaConfig {
    int runs;                       // K runs per row
    int refSpp;                     // path's and bdpt's runs (shared by every row): K of refSpp
    int spp;                        // a row's runs
    int gradientSpp;                // gradient integrators' (noisier primal): a reconstructed_l2 layer
    int metropolisSpp;              // mlt, pmlt, gmlt: their runs, with metropolisBootstrap
    int metropolisBootstrap;        // their "bootstrapsamples"
    int seedX, seedBdpt, seedPath;  // run k: seed + k; disjoint ranges
    double power;                   // the power check's bias
};

// The Metropolis integrators' bootstrap (states per depth; default 100000) is
// a fixed cost per run that dwarfs these scenes' mutations, and the noise of
// the b it estimates dominates a run's image mean (mlt on media-fog, 32 spp,
// 10 runs: run-to-run deviation 1.7% with 20000, 0.75% with 60000); it is part
// of each run's variance, which the tests measure.
inline bool IsMetropolis(const std::string &x) { return x == "mlt" || x == "pmlt" || x == "gmlt"; }

inline void CheckMediaRows(const std::string &scene, const MediaConfig &cfg) {
    ScratchDir dir;
    std::ostringstream config;
    config << "K " << cfg.runs << ", references " << cfg.refSpp << " spp";
    const Runs bdpt = RenderRuns(dir.path(), scene, "bdpt", cfg.runs, cfg.refSpp, cfg.seedBdpt, {});
    const Runs path = RenderRuns(dir.path(), scene, "path", cfg.runs, cfg.refSpp, cfg.seedPath, {});
    ASSERT_FALSE(bdpt.layers.empty() || path.layers.empty()) << "the references do not render " << scene;
    for (const MediaRow &row : MediaRows()) {
        const std::string label = row.label();
        SCOPED_TRACE(label + " on " + scene);
        // One sample per pixel: renders, or refuses with a located error.
        std::vector<std::string> probe = {ScenePath(scene), "--integrator", row.integrator, "--outfile", "probe.exr",
                                          "--quiet", "--spp", "1", "--seed", "1", "--nthreads", "2"};
        probe.insert(probe.end(), row.extra.begin(), row.extra.end());
        const ProcResult r = RunGradus(probe, dir.path());
        if (!r.exited || r.exitCode != 0) {
            EXPECT_FALSE(MustRenderMedia(row)) << label << " refuses " << scene << ": " << r.describe();
            std::cout << "[ media ] " << label << " " << scene << ": refuses\n";
            CheckRefusal(row, scene, r);
            continue;
        }
        AgreementConfig unused{0, 0, 0, 0};
        std::string why;
        if (!AgreementSetup(row.integrator, scene, &unused, &why)) {
            std::cout << "[ media ] " << label << " " << scene << ": renders, not compared: " << why << "\n";
            continue;
        }
        const auto t0 = std::chrono::steady_clock::now();
        const bool isPath = label == "path", isBdpt = label == "bdpt";
        int spp = cfg.spp;
        std::vector<std::string> extra = row.extra;
        if (IsMetropolis(row.integrator)) {
            spp = cfg.metropolisSpp;
            extra.insert(extra.end(), {"--param", "bootstrapsamples=" + std::to_string(cfg.metropolisBootstrap)});
        } else if (ComparedLayers(ReadImage((dir.path() / "probe.exr").string())).size() > 1) {
            spp = cfg.gradientSpp;
        }
        const Runs x = isPath   ? path
                       : isBdpt ? bdpt
                                : RenderRuns(dir.path(), scene, row.integrator, cfg.runs, spp, cfg.seedX, extra);
        if (x.layers.empty()) continue;
        std::cout << "[ media ] " << label << " " << scene << ": renders (" << cfg.runs << " runs of "
                  << (isPath || isBdpt ? cfg.refSpp : spp) << " spp, "
                  << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s)\n";
        const double alphaLayer = kAgreementAlpha / double(x.layers.size());
        if (isPath || isBdpt)
            CompareRuns(label, scene, x, isPath ? "bdpt" : "path", {&(isPath ? bdpt : path).reduced.at("")},
                        alphaLayer, cfg.power, config.str());
        else
            CompareRuns(label, scene, x, "(path+bdpt)/2", {&path.reduced.at(""), &bdpt.reduced.at("")}, alphaLayer,
                        cfg.power, config.str());
    }
}

}  // namespace gradus::conformance
