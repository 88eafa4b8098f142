// Every integrator of the registry either declares rendersSubsurface() and
// builds a scene with a BSSRDF, or refuses it with a located error
// (file:line:column): at the Integrator directive when the scene has one, else
// (--integrator on a scene without one) at the subsurface material; the message
// names the integrator and the material's place.
#include <gtest/gtest.h>

#include <string>

#include "core/error.h"
#include "integrators/registry.h"
#include "job/job.h"
#include "parser/scene_desc.h"

namespace gradus {
namespace {

// The Integrator directive (when given) at test.pbrt:4:3, the material at 8:3.
std::string Scene(const std::string &integrator) {
    return "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n"
           "Film \"image\" \"integer xresolution\" [8] \"integer yresolution\" [8]\n" +
           (integrator.empty() ? std::string("\n") : "  Integrator \"" + integrator + "\"\n") +
           "WorldBegin\nLightSource \"point\" \"point from\" [0 2 2]\nAttributeBegin\n"
           "  Material \"kdsubsurface\" \"rgb Kd\" [0.5 0.5 0.5]\nShape \"sphere\"\nAttributeEnd\nWorldEnd\n";
}

// The error of building the job ("" when it builds).
std::string BuildError(const std::string &text, const std::string &override) {
    BuildOptions bo;
    bo.integratorOverride = override;
    bo.checkOutput = false;
    bo.quiet = true;
    try {
        BuildRenderJob(ParseString(text, "test.pbrt"), bo);
    } catch (const Error &e) {
        return e.what();
    }
    return "";
}

TEST(SubsurfaceRefusal, EveryIntegratorRendersOrRefusesWithALocation) {
    int refusing = 0, rendering = 0;
    for (const IntegratorInfo &info : IntegratorRegistry()) {
        EntityDesc d;
        d.type = info.name;
        const bool renders = CreateIntegrator(d)->rendersSubsurface();
        const std::string named = BuildError(Scene(info.name), ""), overridden = BuildError(Scene(""), info.name);
        if (renders) {
            ++rendering;
            EXPECT_EQ(named, "") << info.name;
            EXPECT_EQ(overridden, "") << info.name;
            continue;
        }
        ++refusing;
        const std::string who = "Integrator \"" + info.name + "\"", material = "(material made at test.pbrt:8:3)";
        EXPECT_EQ(named.rfind("test.pbrt:4:3: " + who + " does not render subsurface scattering", 0), 0u)
            << info.name << ": " << named;
        EXPECT_NE(named.find(material), std::string::npos) << named;
        EXPECT_EQ(overridden.rfind("test.pbrt:8:3: " + who + " does not render subsurface scattering", 0), 0u)
            << info.name << " (--integrator): " << overridden;
        EXPECT_NE(overridden.find(material), std::string::npos) << overridden;
    }
    std::printf("%d integrators render BSSRDFs, %d refuse them\n", rendering, refusing);
    EXPECT_GE(rendering, 1);  // path
    EXPECT_GE(refusing, 1);
}

}  // namespace
}  // namespace gradus
