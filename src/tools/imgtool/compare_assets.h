// The comparison viewer's static files (src/tools/imgtool/compare/), embedded
// at build time by compare/embed.cmake.
#pragma once

namespace gradus {

struct CompareAsset {
    const char *name;  // file name in the page's folder
    const char *text;
};
extern const CompareAsset kCompareAssets[];
extern const int kNumCompareAssets;

}  // namespace gradus
