// Default tier of the M-BDPT / BDPT agreement tests (see unbiased_util.h).
#include "unbiased_util.h"

namespace gradus::mbdpt_test {
namespace {

TEST(MBDPTUnbiased, DistanceReorder) {
    ExpectAgreement("\"string reorder\" \"distance\" \"integer connections\" 1", 100);
    ExpectAgreement("\"string reorder\" \"distance\" \"integer connections\" 2", 200);
    ExpectAgreement("\"string reorder\" \"distance\" \"integer connections\" 4", 300);
}

// "pixel": camera subpaths generated at connection time, column coordinates and
// row participation from the pixel sample's own dimensions, kept light BSDFs.
TEST(MBDPTUnbiased, PixelSampler) {
    ExpectAgreement("\"string matrixsampler\" \"pixel\" \"integer connections\" 1", 1700);
    ExpectAgreement("\"string matrixsampler\" \"pixel\" \"integer connections\" 3", 1800);
    ExpectAgreement("\"string matrixsampler\" \"pixel\" \"string matrixrows\" \"all\"", 1900);
}

// Next-event estimation through the matrix (M_{1,t}), with the strategy
// images; and the paper's configuration (all rows, no roulette, M_{1,t}).
TEST(MBDPTUnbiased, NextEventThroughTheMatrix) {
    ExpectAgreement("\"bool nexteventmatrix\" [true]", 2100, true);
    ExpectAgreement("\"string configuration\" \"paper\"", 2200);
}

}  // namespace
}  // namespace gradus::mbdpt_test
