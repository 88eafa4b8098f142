// Slow tier of the conformance table's agreement check (agreement.h): the same
// test with K = 40 runs of 64 spp per integrator and scene (20x the default
// tier's samples), sensitive to biases of about 1-2% of a row band or block;
// power margins for a 5% bias 7.8-12.8. Measured on the 2 shared cores (load
// average 6-9 from other jobs): 14 min wall, 7 min CPU.
#include <gtest/gtest.h>

#include "agreement.h"
#include "media_rows.h"

using namespace gradus::conformance;

class AgreementSlow : public ::testing::TestWithParam<AgreementParam> {};

TEST_P(AgreementSlow, AgreesWithBdpt) {
    // gmlt: the default tier's reason (conformance_test.cpp), 8x the spp here too.
    const std::string &x = std::get<0>(GetParam());
    AgreementConfig cfg = x == "gmlt" ? AgreementConfig{40, 512, 3000, 5000} : AgreementConfig{40, 64, 3000, 5000};
    std::string why;
    if (!AgreementSetup(x, std::get<1>(GetParam()), &cfg, &why)) GTEST_SKIP() << why;
    CheckAgreement(x, std::get<1>(GetParam()), cfg);
}

INSTANTIATE_TEST_SUITE_P(conformance_slow, AgreementSlow,
                         ::testing::Combine(::testing::ValuesIn(Integrators()), ::testing::ValuesIn(Scenes())),
                         AgreementName);

// Media rows (media_rows.h) with the 2% power check: K = 40 runs, references of
// 128 spp, rows of 64 spp (mlt: its default bootstrap of 100000 states per
// depth); media-interface, the least noisy, with half the samples. Smallest
// power margins (|t|/critical of a 2% bias): media-fog 1.41, media-grid 1.29
// (gpt's primal), media-interface 2.43 (mlt). Measured on the 2 shared cores
// (load average 6): media-fog 186 s, media-grid 306 s, media-interface 102 s
// wall (CPU about the same).
class MediaTableSlow : public ::testing::TestWithParam<std::string> {};

TEST_P(MediaTableSlow, RefusesOrAgrees) {
    const std::string &scene = GetParam();
    const MediaConfig cfg = scene == "media-interface" ? MediaConfig{40, 64, 32, 32, 32, 100000, 3000, 5000, 7000, 1.02}
                                                       : MediaConfig{40, 128, 64, 64, 64, 100000, 3000, 5000, 7000, 1.02};
    CheckMediaRows(scene, cfg);
}

INSTANTIATE_TEST_SUITE_P(conformance_slow, MediaTableSlow, ::testing::ValuesIn(MediaScenes()),
                         [](const ::testing::TestParamInfo<std::string> &info) { return Sanitize(info.param); });
