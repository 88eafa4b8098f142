// G-BDPT with participating media against bdpt, slow tier (statistics in
// gpt/gpt_media_check.h; the smoke wedges run in the fast tier, test_media.cpp):
// fog-box (homogeneous fog, spot and area light, a material-less smoke
// sphere: a medium interface between two media inside the scene). Measured:
// 44 s on 2 loaded cores.
#include "gpt/gpt_media_check.h"

using namespace gradus::gptmedia;

TEST(GBDPTMediaSlow, AgreesWithBDPTOnFogBox) {
    CheckAgainstPath("gbdpt fog-box", FogBoxText(), 16, 64, 900, 0.03, "gbdpt", "bdpt", true);
}
