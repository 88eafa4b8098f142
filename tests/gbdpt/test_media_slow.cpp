// G-BDPT with participating media against bdpt, slow tier (statistics in
// gpt/gpt_media_check.h; the smoke wedges run in the fast tier, test_media.cpp):
//  - fog-box (homogeneous fog, spot and area light, a material-less smoke
//    sphere: a medium interface between two media inside the scene);
//  - the smoke wedge with a glass sphere inside the smoke, a near-specular
//    metal sphere and an environment light: first chains through Dirac and
//    near-specular vertices between medium vertices, environment shifts out of
//    the smoke, and second chains through specular vertices (not walked with
//    media: those paths fall back in every strategy, gbdpt.h).
#include "gpt/gpt_media_check.h"

using namespace gradus::gptmedia;

TEST(GBDPTMediaSlow, AgreesWithBDPTOnFogBox) {
    CheckAgainstPath("gbdpt fog-box", FogBoxText(), 16, 64, 900, 0.03, "gbdpt", "bdpt", true);
}

TEST(GBDPTMediaSlow, AgreesWithBDPTOnSmokeWedgeWithSpecularSpheres) {
    CheckAgainstPath("gbdpt smoke-wedge-specular",
                     WedgeSpecularText("Integrator \"gbdpt\" \"integer maxdepth\" [4]"), 16, 128, 150, 0.02, "gbdpt",
                     "bdpt", true);
}
