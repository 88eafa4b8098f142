// Slow tier of the M-BDPT / BDPT agreement tests (see unbiased_util.h).
#include "unbiased_util.h"

namespace gradus::mbdpt_test {
namespace {

TEST(MBDPTUnbiased, MortonReorder) {
    ExpectAgreement("\"string reorder\" \"morton\" \"integer connections\" 1", 400);
    ExpectAgreement("\"string reorder\" \"morton\" \"integer connections\" 2", 500);
    ExpectAgreement("\"string reorder\" \"morton\" \"integer connections\" 4", 600);
}

TEST(MBDPTUnbiased, NoReorder) {
    ExpectAgreement("\"string reorder\" \"none\" \"integer connections\" 1", 700);
    ExpectAgreement("\"string reorder\" \"none\" \"integer connections\" 2", 800);
    ExpectAgreement("\"string reorder\" \"none\" \"integer connections\" 4", 900);
}

TEST(MBDPTUnbiased, SamplersRowsAndCombinatorial) {
    ExpectAgreement("\"string matrixsampler\" \"lhs\" \"integer connections\" 2", 1000);
    ExpectAgreement("\"string matrixsampler\" \"random\"", 1100);
    ExpectAgreement("\"string matrixsampler\" \"diagonal\"", 1200);
    ExpectAgreement("\"string matrixrows\" \"all\"", 1300);
    ExpectAgreement("\"bool combinatorial\" [true]", 1400);
}

// Per-(s, t) images (MIS-weighted contribution of each strategy) equal BDPT's in expectation.
TEST(MBDPTUnbiased, StrategyImages) {
    ExpectAgreement("\"string reorder\" \"distance\"", 1500, true);
    ExpectAgreement("\"string reorder\" \"morton\" \"integer connections\" 2 \"string matrixrows\" \"all\"", 1600, true);
    ExpectAgreement("\"string matrixsampler\" \"pixel\" \"integer connections\" 2", 2000, true);
}

TEST(MBDPTUnbiased, NextEventThroughTheMatrixModes) {
    ExpectAgreement("\"bool nexteventmatrix\" [true] \"string matrixsampler\" \"pixel\"", 2300, true);
    ExpectAgreement("\"bool nexteventmatrix\" [true] \"string reorder\" \"morton\" \"integer connections\" 2", 2400);
    ExpectAgreement("\"bool nexteventmatrix\" [true] \"bool combinatorial\" [true]", 2500);
    ExpectAgreement("\"bool nexteventmatrix\" [true] \"string matrixsampler\" \"diagonal\"", 2600);
}

}  // namespace
}  // namespace gradus::mbdpt_test
