// G-PT with participating media against path on fog-box and its density-grid
// variant (statistics in gpt_media_check.h); the smoke wedge runs in the fast
// tier (test_gpt_media.cpp).
#include "gpt_media_check.h"

using namespace gradus::gptmedia;

// Power: a 2% bias gives |t| ~ 4.5 here (critical 5.35) at this run time; 3% is asserted.
TEST(GPTMediaSlow, AgreesWithPathOnFogBox) { CheckAgainstPath("fog-box", FogBoxText(), 16, 128, 900, 0.03); }

TEST(GPTMediaSlow, AgreesWithPathOnGridFogBox) {
    CheckAgainstPath("grid-fog-box", GridFogBoxText(), 16, 128, 900, 0.03);
}
