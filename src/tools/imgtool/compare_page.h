// imgtool compare: a static HTML page comparing renders against a reference,
// tone-mapped in the browser (WebGL2) from the linear data.
#pragma once
#include <string>
#include <vector>

#include "image/image.h"
#include "image/metrics.h"

namespace gradus {

struct ComparePageInput {
    std::string path;   // image file
    std::string label;  // shown in the page ("" = the file name without extension)
    std::string layer;  // "" = the default RGB layer (for the reference: --ref-layer)
};

struct ComparePageOptions {
    std::string title;        // "" = "Gradus comparison: A, B against REF" (labels)
    double exposure = 0;      // initial exposure (EV)
    double errorMax = 0;      // initial top of the relative-error ramp (0 = from the data)
    CompareOptions metrics;   // epsilon and trimming of the figures (layers come from the inputs)
};

struct ComparePageSummary {
    std::vector<std::string> files;  // written, relative to the folder
    size_t bytes = 0;                // their total size
    double errorMax = 0;             // the error ramp's initial top
    std::vector<ImageMetrics> metrics;  // per test image (inputs[1..])
};

// Writes index.html, viewer.js, viewer.css, data.js and img-K.js (K = 0 for the
// reference, then one per test image) into `dir` (created if needed). inputs[0]
// is the reference. Every image is read, and all must have the reference's size,
// before anything is written. Throws gradus::Error on any problem.
ComparePageSummary WriteComparePage(const std::string &dir, const std::vector<ComparePageInput> &inputs,
                                    const ComparePageOptions &opts);

// The q-quantile (q in [0,1]) of an ErrorImage's per-pixel "relmse" over the
// pixels not excluded; 0 when none.
double ErrorQuantile(const Image &err, double q);

}  // namespace gradus
