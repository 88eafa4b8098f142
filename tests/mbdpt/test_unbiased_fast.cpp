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

}  // namespace
}  // namespace gradus::mbdpt_test
