#include "render/scene_builder.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <sstream>
#include <thread>
#include <chrono>

#include <sys/resource.h>

#include "core/error.h"
#include "core/provenance.h"
#include "parser/ply.h"
#include "render/checkpoint.h"
#include "samplers/sampling.h"
#include "shapes/curve.h"
#include "shapes/heightfield.h"
#include "shapes/loopsubdiv.h"
#include "shapes/nurbs.h"
#include "shapes/quadrics.h"
#include "shapes/sphere.h"

namespace gradus {

namespace {

struct ShapeBuild {
    std::shared_ptr<TriangleMesh> mesh;
    std::shared_ptr<AnalyticShape> analytic;
    std::shared_ptr<CurveShape> curve;
    bool subdivision = false;
};

// pbrt-v3 alpha parameters: "texture alpha" names a float texture; a constant
// "float alpha" 0 cuts the whole mesh away, any other constant keeps it.
std::shared_ptr<const FloatTexture> AlphaTexture(const ParamSet &ps, const std::string &name, const FileLoc &loc,
                                                 const NamedTextures &textures) {
    if (!ps.has(name)) return nullptr;
    std::string tex = ps.getTexture(name);
    if (!tex.empty()) {
        auto it = textures.floats.find(tex);
        if (it == textures.floats.end())
            throw Error(ps.locOf(name, loc), "\"" + name + "\": unknown float texture \"" + tex + "\"");
        return it->second;
    }
    if (ps.getFloat(name, 1) == 0) return std::make_shared<ConstantTexture<Float>>(0);
    return nullptr;
}

ShapeBuild CreateShape(const ShapeDesc &sd, const SceneDesc &scene, const NamedTextures &textures) {
    const ParamSet &ps = sd.params;
    const std::string &t = sd.type;
    const Transform &xf = sd.worldFromObject;
    const bool ro = sd.reverseOrientation;
    ShapeBuild b;
    auto setAlpha = [&]() {
        b.mesh->alpha = AlphaTexture(ps, "alpha", sd.loc, textures);
        b.mesh->shadowAlpha = AlphaTexture(ps, "shadowalpha", sd.loc, textures);
    };
    auto positive = [&](const char *name, Float v) {
        if (!(v > 0) || !std::isfinite(v))
            throw Error(ps.locOf(name, sd.loc), "Shape \"" + t + "\": \"" + name + "\" must be > 0 and finite");
    };
    auto finiteParam = [&](const char *name, Float v) {
        if (!std::isfinite(v)) throw Error(ps.locOf(name, sd.loc), "Shape \"" + t + "\": \"" + name + "\" is not finite");
    };
    if (t == "trianglemesh") {
        std::vector<int> idx = ps.getInts("indices");
        std::vector<Point3> P = ps.getPoint3s("P");
        if (P.empty()) throw Error(sd.loc, "trianglemesh: missing \"point P\"");
        if (idx.empty()) {
            if (P.size() == 3) idx = {0, 1, 2};
            else throw Error(sd.loc, "trianglemesh: missing \"integer indices\"");
        }
        std::vector<Point2> uv = ps.getPoint2s("uv");
        if (uv.empty()) uv = ps.getPoint2s("st");
        std::vector<Normal3> N = ps.getNormals("N");
        std::vector<Vec3> S = ps.getVector3s("S");
        b.mesh = TriangleMesh::Create(xf, ro, std::move(P), std::move(idx), std::move(N), std::move(S),
                                      std::move(uv), sd.loc);
        setAlpha();
    } else if (t == "plymesh") {
        std::string fn = ps.getString("filename", "");
        if (fn.empty()) throw Error(sd.loc, "plymesh: missing \"string filename\"");
        PlyMesh ply;
        try {
            ply = ReadPly(scene.resolve(fn));
        } catch (const Error &e) {
            throw Error(ps.locOf("filename", sd.loc), e.what());
        }
        if (ps.has("displacement")) throw UnsupportedError(ps.locOf("displacement", sd.loc), "plymesh displacement");
        b.mesh = TriangleMesh::Create(xf, ro, std::move(ply.P), std::move(ply.indices), std::move(ply.N), {},
                                      std::move(ply.uv), ps.locOf("filename", sd.loc));
        setAlpha();
    } else if (t == "loopsubdiv") {
        int levels = ps.getInt("levels", 3);
        if (ps.has("nlevels")) levels = ps.getInt("nlevels", levels);
        std::vector<int> idx = ps.getInts("indices");
        std::vector<Point3> P = ps.getPoint3s("P");
        if (P.empty()) throw Error(sd.loc, "loopsubdiv: missing \"point P\"");
        if (idx.empty()) throw Error(sd.loc, "loopsubdiv: missing \"integer indices\"");
        LoopSubdivResult sub = LoopSubdivide(P, idx, levels, sd.loc);
        b.mesh = TriangleMesh::Create(xf, ro, std::move(sub.P), std::move(sub.indices), std::move(sub.N), {}, {},
                                      sd.loc);
        b.subdivision = true;
    } else if (t == "sphere") {
        Float r = ps.getFloat("radius", 1);
        Float zmin = ps.getFloat("zmin", -r), zmax = ps.getFloat("zmax", r), phimax = ps.getFloat("phimax", 360);
        positive("radius", r);
        finiteParam("zmin", zmin), finiteParam("zmax", zmax), finiteParam("phimax", phimax);
        b.analytic = std::make_shared<Sphere>(xf, ro, r, zmin, zmax, phimax);
    } else if (t == "disk") {
        Float h = ps.getFloat("height", 0), r = ps.getFloat("radius", 1), ri = ps.getFloat("innerradius", 0);
        Float phimax = ps.getFloat("phimax", 360);
        positive("radius", r);
        finiteParam("height", h), finiteParam("phimax", phimax);
        if (!(ri >= 0 && ri < r))
            throw Error(ps.locOf("innerradius", sd.loc), "disk: \"innerradius\" must be in [0, radius)");
        b.analytic = std::make_shared<Disk>(xf, ro, h, r, ri, phimax);
    } else if (t == "cylinder") {
        Float r = ps.getFloat("radius", 1), zmin = ps.getFloat("zmin", -1), zmax = ps.getFloat("zmax", 1);
        Float phimax = ps.getFloat("phimax", 360);
        positive("radius", r);
        finiteParam("zmin", zmin), finiteParam("zmax", zmax), finiteParam("phimax", phimax);
        b.analytic = std::make_shared<Cylinder>(xf, ro, r, zmin, zmax, phimax);
    } else if (t == "cone") {
        Float h = ps.getFloat("height", 1), r = ps.getFloat("radius", 1), phimax = ps.getFloat("phimax", 360);
        positive("height", h), positive("radius", r), finiteParam("phimax", phimax);
        b.analytic = std::make_shared<Cone>(xf, ro, h, r, phimax);
    } else if (t == "paraboloid") {
        Float r = ps.getFloat("radius", 1), zmin = ps.getFloat("zmin", 0), zmax = ps.getFloat("zmax", 1);
        Float phimax = ps.getFloat("phimax", 360);
        positive("radius", r), finiteParam("zmin", zmin), finiteParam("phimax", phimax);
        if (!(std::max(zmin, zmax) > 0) || !std::isfinite(zmax))
            throw Error(ps.locOf("zmax", sd.loc), "paraboloid: \"zmax\" must be > 0 and finite");
        b.analytic = std::make_shared<Paraboloid>(xf, ro, r, zmin, zmax, phimax);
    } else if (t == "hyperboloid") {
        Point3 p1 = ps.getPoint3("p1", Point3(0, 0, 0)), p2 = ps.getPoint3("p2", Point3(1, 1, 1));
        Float phimax = ps.getFloat("phimax", 360);
        finiteParam("phimax", phimax);
        if (!p1.isFinite() || !p2.isFinite()) throw Error(sd.loc, "hyperboloid: \"p1\"/\"p2\" not finite");
        if (p1.z == p2.z)
            throw UnsupportedError(ps.locOf("p2", sd.loc),
                                   "hyperboloid with p1.z == p2.z (a flat annulus: use a \"disk\")");
        b.analytic = std::make_shared<Hyperboloid>(xf, ro, p1, p2, phimax);
    } else if (t == "heightfield" || t == "nurbs") {
        MeshData m = t == "heightfield" ? CreateHeightfield(ps, sd.loc) : CreateNurbs(ps, sd.loc);
        b.mesh = TriangleMesh::Create(xf, ro, std::move(m.P), std::move(m.indices), std::move(m.N), {},
                                      std::move(m.uv), sd.loc);  // no alpha: pbrt-v3 reads none for these
    } else if (t == "curve") {
        b.curve = CreateCurveShape(ps, xf, ro, sd.loc);
    } else {
        throw Error(sd.loc, "unknown shape \"" + t +
                                "\" (valid: trianglemesh, plymesh, loopsubdiv, sphere, disk, cylinder, cone, "
                                "paraboloid, hyperboloid, heightfield, nurbs, curve)");
    }
    ps.checkUnused("Shape \"" + t + "\"");
    return b;
}

}  // namespace

namespace {
double CpuSeconds() {
    rusage u;
    getrusage(RUSAGE_SELF, &u);
    return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}
// Embree traces in single precision and rejects ray origins beyond ~1.8e18:
// geometry (and anything rays would start from) must stay within 1e15 of the
// origin, or the renderer would abort inside Embree.
void CheckTraceableBounds(const Bounds3 &b, const FileLoc &loc) {
    constexpr Float kMax = 1e15;
    for (int i = 0; i < 3; ++i)
        if (!(std::abs(b.pMin[i]) <= kMax && std::abs(b.pMax[i]) <= kMax))
            throw Error(loc, "shape extends beyond 1e15 scene units from the origin (the range the ray tracer handles)");
}
// The process's own peak: /proc's VmHWM. getrusage's ru_maxrss survives
// execve, so a process started by a large parent (a benchmark script holding a
// mesh) would report the parent's size; it is the fallback without /proc.
double PeakRSSMegabytes() {
    if (FILE *f = std::fopen("/proc/self/status", "r")) {
        char line[256];
        long kb = -1;
        while (std::fgets(line, sizeof line, f))
            if (std::sscanf(line, "VmHWM: %ld kB", &kb) == 1) break;
        std::fclose(f);
        if (kb >= 0) return kb / 1024.0;
    }
    rusage u;
    getrusage(RUSAGE_SELF, &u);
    return u.ru_maxrss / 1024.0;  // ru_maxrss is in KiB on Linux
}
}  // namespace

// Media and BSSRDFs are refused by integrators that do not render them,
// naming the integrator and the scene part (never a silently wrong image).
constexpr const char *kMediaIntegrators = "path (pbrt-v3's volpath), bdpt, mbdpt and vcm (modes vcm and vc)";
static void RefuseUnhandledParts(const Integrator &integrator, const Scene &scene, const SceneDesc &desc,
                          const EntityDesc &idesc) {
    const FileLoc at = idesc.present ? idesc.loc : (desc.media.empty() ? FileLoc() : desc.media.front().loc);
    if (scene.features.media && !integrator.rendersMedia()) {
        const MediumDesc &m = desc.media.front();
        throw Error(at, "Integrator \"" + idesc.type + "\" does not render participating media (medium \"" + m.name +
                            "\" made at " + m.loc.str() + "); media render with " + kMediaIntegrators);
    }
    if (scene.features.subsurface && !integrator.rendersSubsurface()) {
        FileLoc mloc;
        for (const MaterialDesc &md : desc.materials)
            if (md.type == "subsurface" || md.type == "kdsubsurface") {
                mloc = md.loc;
                break;
            }
        throw Error(at, "Integrator \"" + idesc.type + "\" does not render subsurface scattering (material made at " +
                            mloc.str() + "); BSSRDFs render with path");
    }
    if (!scene.camera->hasImportance() && !integrator.rendersCamerasWithoutImportance())
        throw Error(idesc.present ? idesc.loc : desc.camera.loc,
                    "Integrator \"" + idesc.type + "\" does not render Camera \"" + desc.camera.type + "\" (made at " +
                        desc.camera.loc.str() + "), which has no importance function for light-to-camera "
                        "connections; it renders with path and bdpt (bdpt without its light-tracing strategies)");
}

std::unique_ptr<Scene> BuildScene(const SceneDesc &desc, Point2i resolution) {
    // pbrt-v3 features that would otherwise be dropped silently.
    if (desc.motionBlur)
        throw UnsupportedError(desc.motionLoc, "motion blur (this entity's start and end transforms differ)");
    auto scene = std::make_unique<Scene>();
    SceneFeatures &feat = scene->features;

    // Media (MakeNamedMedium); names were checked by the parser. "" is vacuum.
    std::map<std::string, const Medium *> mediumByName;
    for (const MediumDesc &md : desc.media) {
        auto m = CreateMedium(md);
        md.params.checkUnused("MakeNamedMedium \"" + md.name + "\"");
        mediumByName[md.name] = m.get();
        scene->media.push_back(std::move(m));
    }
    auto mediumNamed = [&](const std::string &name) -> const Medium * {
        if (name.empty()) return nullptr;
        feat.media = true;
        return mediumByName.at(name);
    };
    auto interfaceOf = [&](const ShapeDesc &sd) {
        MediumInterface mi;
        mi.inside = mediumNamed(sd.insideMedium);
        mi.outside = mediumNamed(sd.outsideMedium);
        return mi;
    };

    // Textures (in file order: later ones may reference earlier ones).
    NamedTextures textures;
    for (const auto &td : desc.textures) {
        CreateTexture(td, desc, &textures);
        td.params.checkUnused("Texture \"" + td.name + "\"");
        if (td.type != "constant") feat.textures = true;
    }
    // Materials; "none"/"interface"/"" mean no surface (rays pass through).
    std::vector<const Material *> matByIndex(desc.materials.size(), nullptr);
    std::map<std::string, std::shared_ptr<Material>> named;
    feat.minRoughness = 1;
    for (size_t i = 0; i < desc.materials.size(); ++i) {
        const MaterialDesc &md = desc.materials[i];
        if (md.type.empty() || md.type == "none" || md.type == "interface") {
            md.params.checkUnused("Material \"" + md.type + "\"");
            continue;
        }
        auto m = CreateMaterial(md, textures, named, &desc);
        md.params.checkUnused("Material \"" + md.type + "\"");
        if (!md.name.empty()) named[md.name] = m;
        matByIndex[i] = m.get();
        scene->materials.push_back(m);
    }
    MaterialDesc defDesc;
    defDesc.type = "matte";
    auto defaultMaterial = CreateMaterial(defDesc, textures, named);
    scene->materials.push_back(defaultMaterial);

    // Shapes: world shapes and object instances. An object used more than once
    // becomes an Embree instance: its triangle meshes are built and stored once,
    // in the object's space, and every use adds only a transform (records with
    // a MeshPlacement). Its analytic shapes and alpha-cut meshes, and objects
    // used once, are flattened into world shapes (transformed copies).
    std::vector<ShapeDesc> shapes = desc.shapes;
    std::map<std::string, int> uses;
    for (const auto &use : desc.instanceUses) {
        auto it = desc.instances.find(use.name);
        if (it == desc.instances.end()) throw Error(use.loc, "unknown object \"" + use.name + "\"");
        for (const ShapeDesc &s : it->second.shapes)
            if (s.areaLight >= 0) throw UnsupportedError(s.loc, "area lights inside object instances");
        ++uses[use.name];
    }
    auto materialOf = [&](const ShapeDesc &sd) {
        if (sd.material >= 0 && matByIndex[sd.material]) {
            feat.minRoughness = std::min(feat.minRoughness, matByIndex[sd.material]->minRoughness());
            if (matByIndex[sd.material]->hasSubsurface()) feat.subsurface = true;
        }
        return sd.material >= 0 ? matByIndex[sd.material] : defaultMaterial.get();
    };
    struct ObjectBuild {
        int embreeObject = -1;
        std::vector<const Material *> materials;  // per mesh of the Embree object
        std::vector<MediumInterface> media;       // per mesh of the Embree object
        Bounds3 bounds;                           // of those meshes, in the object's space
        int64_t triangles = 0;
        std::vector<ShapeDesc> flattened;  // shapes copied per use
    };
    std::map<std::string, ObjectBuild> objects;
    std::vector<std::pair<const InstanceUseDesc *, const ObjectBuild *>> instanced;
    auto flatten = [&](const std::vector<ShapeDesc> &objectShapes, const Transform &worldFromInstance) {
        for (ShapeDesc s : objectShapes) {
            s.worldFromObject = worldFromInstance * s.worldFromObject;
            shapes.push_back(std::move(s));
        }
    };
    for (const auto &use : desc.instanceUses) {
        const InstanceDesc &inst = desc.instances.at(use.name);
        if (uses[use.name] == 1) {  // nothing to share
            flatten(inst.shapes, use.worldFromInstance);
            continue;
        }
        auto [found, isNew] = objects.try_emplace(use.name);
        if (isNew) {
            ObjectBuild &ob = found->second;
            for (const ShapeDesc &sd : inst.shapes) {
                ShapeBuild b = CreateShape(sd, desc, textures);
                if (!b.mesh || b.mesh->alpha || b.mesh->shadowAlpha) {
                    ob.flattened.push_back(sd);
                    continue;
                }
                if (b.mesh->numTriangles() == 0) continue;
                if (b.subdivision) feat.subdivisionSurfaces = true;
                if (ob.embreeObject < 0) ob.embreeObject = scene->accel.newObject();
                for (const auto &q : b.mesh->p) ob.bounds.expand(q);
                ob.triangles += b.mesh->numTriangles();
                ob.materials.push_back(materialOf(sd));
                ob.media.push_back(interfaceOf(sd));
                scene->accel.addObjectMesh(ob.embreeObject, b.mesh);
            }
            feat.numStoredTriangles += ob.triangles;
        }
        const ObjectBuild &ob = found->second;
        if (ob.embreeObject >= 0) CheckTraceableBounds(use.worldFromInstance.applyBounds(ob.bounds), use.loc);
        flatten(ob.flattened, use.worldFromInstance);
        if (ob.embreeObject >= 0) instanced.emplace_back(&use, &ob);
    }
    for (const auto &sd : shapes) {
        ShapeBuild b = CreateShape(sd, desc, textures);
        GeometryRecord rec;
        rec.material = materialOf(sd);
        rec.mediumInterface = interfaceOf(sd);
        if (b.mesh) {
            if (b.mesh->numTriangles() == 0) continue;  // empty mesh: nothing to add
            rec.mesh = b.mesh;
            feat.numTriangles += b.mesh->numTriangles();
            feat.numStoredTriangles += b.mesh->numTriangles();
            if (b.subdivision) feat.subdivisionSurfaces = true;
            Bounds3 sb;
            for (const auto &p : b.mesh->p) sb.expand(p);
            CheckTraceableBounds(sb, sd.loc);
            scene->bounds.expand(sb);
        } else if (b.curve) {
            rec.curve = b.curve;
            feat.numCurveSegments += b.curve->numSegments();
            CheckTraceableBounds(b.curve->worldBound(), sd.loc);
            scene->bounds.expand(b.curve->worldBound());
        } else {
            rec.analytic = b.analytic;
            rec.sphere = b.analytic;
            if (dynamic_cast<const Sphere *>(b.analytic.get())) feat.numSpheres++;
            else feat.numAnalytic++;
            CheckTraceableBounds(b.analytic->worldBound(), sd.loc);
            scene->bounds.expand(b.analytic->worldBound());
        }
        if (sd.areaLight >= 0 && b.curve)  // pbrt-v3 allows it (rarely used); not supported here
            throw UnsupportedError(desc.areaLights[sd.areaLight].loc, "an area light on a \"curve\" shape (made at " +
                                                                          sd.loc.str() + ")");
        if (sd.areaLight >= 0) {
            const EntityDesc &ad = desc.areaLights[sd.areaLight];
            if (ad.type != "diffuse" && ad.type != "area")
                throw Error(ad.loc, "unknown area light \"" + ad.type + "\" (valid: diffuse, area)");
            Spectrum L = ad.params.getSpectrum("L", Spectrum(1), SpectrumKind::Illuminant) * ad.params.getSpectrum("scale", Spectrum(1));
            bool twoSided = ad.params.getBool("twosided", false);
            // Gradus extension (glTF emissive textures): "texture Lmap" scales L per
            // triangle by the texture's mean over the triangle (4x4 stratified
            // barycentric points): emission stays piecewise constant per triangle.
            std::shared_ptr<SpectrumTexture> lmap;
            if (ad.params.has("Lmap")) {
                std::string tn = ad.params.getTexture("Lmap");
                auto it = textures.spectra.find(tn);
                if (tn.empty() || it == textures.spectra.end())
                    throw Error(ad.params.locOf("Lmap", ad.loc), "\"Lmap\": unknown spectrum texture \"" + tn + "\"");
                if (!b.mesh) throw UnsupportedError(ad.params.locOf("Lmap", ad.loc), "\"Lmap\" on non-triangle shapes");
                lmap = it->second;
            }
            ad.params.getInt("nsamples", 1);
            ad.params.checkUnused("AreaLightSource \"" + ad.type + "\"");
            if (b.mesh) {
                for (int t = 0; t < b.mesh->numTriangles(); ++t) {
                    auto tri = std::make_shared<Triangle>(b.mesh, t);
                    if (!(tri->area() > 0)) {  // zero-area triangles emit nothing
                        rec.areaLights.push_back(nullptr);
                        continue;
                    }
                    Spectrum Lt = L;
                    if (lmap) {
                        Spectrum sum(0);
                        for (int i = 0; i < 4; ++i)
                            for (int j = 0; j < 4; ++j) {
                                // Stratified uniform points on the triangle (square-root mapping).
                                Float su = std::sqrt((i + 0.5) / 4), v = (j + 0.5) / 4;
                                SurfaceInteraction si;
                                b.mesh->interaction(t, su * (1 - v), su * v, Vec3(0, 0, 1), &si);
                                sum += lmap->evaluate(si);
                            }
                        Lt = L * (sum / 16);
                        if (Lt.isBlack()) {
                            rec.areaLights.push_back(nullptr);
                            continue;
                        }
                    }
                    auto al = std::make_shared<AreaLight>(tri, Lt, twoSided);
                    al->mediumInterface = rec.mediumInterface;
                    rec.areaLights.push_back(al.get());
                    scene->lights.push_back(al);
                }
            } else if (b.analytic->area() > 0) {
                auto al = std::make_shared<AreaLight>(b.analytic, L, twoSided);
                al->mediumInterface = rec.mediumInterface;
                rec.areaLights.push_back(al.get());
                scene->lights.push_back(al);
            } else {
                rec.areaLights.push_back(nullptr);
            }
            feat.areaLights = true;
        }
        int id = b.mesh    ? scene->accel.addMesh(b.mesh)
                 : b.curve ? scene->accel.addCurve(b.curve)
                           : scene->accel.addAnalytic(b.analytic);
        if (id != int(scene->geometry.size())) throw Error("internal: geometry ids out of order");
        scene->geometry.push_back(std::move(rec));
    }
    for (const auto &[use, ob] : instanced) {
        scene->bounds.expand(use->worldFromInstance.applyBounds(ob->bounds));
        scene->placements.push_back(std::make_unique<MeshPlacement>(use->worldFromInstance));
        const MeshPlacement *pl = scene->placements.back().get();
        const int first = scene->accel.addInstance(ob->embreeObject, use->worldFromInstance);
        if (first != int(scene->geometry.size())) throw Error("internal: geometry ids out of order");
        for (int k = 0; k < scene->accel.objectMeshCount(ob->embreeObject); ++k) {
            GeometryRecord rec;
            rec.mesh = scene->accel.objectMesh(ob->embreeObject, k);
            rec.placement = pl;
            rec.material = ob->materials[size_t(k)];
            rec.mediumInterface = ob->media[size_t(k)];
            scene->geometry.push_back(std::move(rec));
        }
        feat.numInstances++;
        feat.numInstancedTriangles += ob->triangles;
        feat.numTriangles += ob->triangles;
    }
    scene->accel.commit();
    if (!scene->bounds.empty()) {
        Point3 c;
        Float r;
        scene->bounds.boundingSphere(&c, &r);
        gRayEpsilon = 1e-6 * std::min<Float>(1, std::max<Float>(r, 1e-6));
    }

    for (const auto &ld : desc.lights) {
        auto l = CreateLight(ld, desc);
        // Lights at a position sit in the medium current at LightSource;
        // lights at infinity send their light in from outside every medium.
        if (!(l->flags & (LIGHT_INFINITE | LIGHT_DELTA_DIRECTION))) {
            l->mediumInterface.inside = l->mediumInterface.outside = mediumNamed(ld.outsideMedium);
        }
        if (l->flags & LIGHT_INFINITE) {
            scene->infiniteLights.push_back(l.get());
            feat.infiniteLights = true;
        }
        if (IsDeltaLight(l->flags)) feat.deltaLights = true;
        scene->lights.push_back(l);
    }
    // Lights at infinity need the scene's bounding sphere (light-tracing
    // densities 1 / (pi r^2)); a world without shapes gets a unit box around
    // the camera instead of an empty one (r = 0 and a NaN centre made every
    // vcm sample non-finite: bench/stress empty_env).
    Bounds3 lightBounds = scene->bounds;
    if (lightBounds.empty()) {
        const Point3 eye = desc.camera.cameraFromWorld.inverse().applyPoint(Point3(0, 0, 0));
        const Point3 c = eye.isFinite() ? eye : Point3(0, 0, 0);
        lightBounds.expand(c - Vec3(1, 1, 1));
        lightBounds.expand(c + Vec3(1, 1, 1));
    }
    for (auto &l : scene->lights) l->preprocess(lightBounds);
    feat.numLights = int(scene->lights.size());
    feat.specularSurfaces = feat.minRoughness == 0;
    feat.nearSpecularSurfaces = feat.minRoughness < kDefaultShiftThreshold;

    scene->camera = CreateCamera(desc.camera, resolution, &desc);
    scene->cameraMedium = mediumNamed(desc.camera.mediumName);

    // Are emitters directly visible? Probe a coarse grid of camera rays.
    const int probe = 64;
    for (int y = 0; y < probe && !feat.emittersDirectlyVisible; ++y)
        for (int x = 0; x < probe; ++x) {
            CameraSample cs;
            cs.pFilm = Point2((x + 0.5) * resolution.x / probe, (y + 0.5) * resolution.y / probe);
            cs.pLens = Point2(0.5, 0.5);
            Ray r;
            scene->camera->generateRay(cs, &r);
            SurfaceInteraction si;
            bool hit = scene->intersect(r, &si);
            if ((hit && si.areaLight) || (!hit && !scene->infiniteLights.empty())) {
                feat.emittersDirectlyVisible = true;
                break;
            }
        }
    return scene;
}

namespace {

// pbrt-v3's "sppm" is vcm's merging-only mode (progressive photon mapping,
// vcm.h), which reads sppm's parameters (numiterations, radius, ...); pbrt-v3's
// defaults of 64 iterations and radius 1 are made explicit.
void MapPbrtSppm(EntityDesc *d) {
    if (d->type != "sppm" || std::none_of(IntegratorRegistry().begin(), IntegratorRegistry().end(),
                                          [](const IntegratorInfo &i) { return i.name == "vcm"; }))
        return;
    auto add = [&](const std::string &type, const std::string &name, double number, const std::string &str) {
        if (d->params.has(name)) return;
        Param p;
        p.type = type;
        p.name = name;
        p.loc = d->loc;
        if (type == "string")
            p.strings = {str};
        else
            p.numbers = {number};
        d->params.add(p);
    };
    add("integer", "numiterations", 64, "");
    add("float", "radius", 1, "");
    add("string", "mode", 0, "vm");
    d->type = "vcm";
}

}  // namespace

RenderJob BuildRenderJob(const SceneDesc &desc, const BuildOptions &opts) {
    RenderJob job;
    job.warnings = desc.notes;
    // Film.
    const EntityDesc &fd = desc.film;
    if (fd.present && fd.type != "image")
        throw Error(fd.loc, "unknown film \"" + fd.type + "\" (valid: image)");
    const ParamSet &fp = fd.params;
    Point2i res{fp.getInt("xresolution", 640), fp.getInt("yresolution", 480)};
    constexpr int kMaxSide = 1 << 17;
    for (const char *n : {"xresolution", "yresolution"}) {
        int v = n[0] == 'x' ? res.x : res.y;
        if (v <= 0 || v > kMaxSide)
            throw Error(fp.locOf(n, fd.loc), std::string("\"") + n + "\" must be in [1, " + std::to_string(kMaxSide) +
                                                 "], got " + std::to_string(v));
    }
    if (opts.resolution.x > 0 && opts.resolution.y > 0) res = opts.resolution;
    if (opts.quick) res = {std::max(1, res.x / 4), std::max(1, res.y / 4)};
    Float crop[4] = {0, 1, 0, 1};
    std::vector<Float> cw = fp.getFloats("cropwindow");
    if (!cw.empty()) {
        if (cw.size() != 4) throw Error(fp.locOf("cropwindow", fd.loc), "\"cropwindow\" needs 4 values");
        for (int i = 0; i < 4; ++i) crop[i] = cw[i];
    }
    if (opts.hasCrop)
        for (int i = 0; i < 4; ++i) crop[i] = opts.crop[i];
    for (int i = 0; i < 4; ++i) crop[i] = Clamp<Float>(crop[i], 0, 1);
    if (crop[0] > crop[1]) std::swap(crop[0], crop[1]);
    if (crop[2] > crop[3]) std::swap(crop[2], crop[3]);
    std::string filename = fp.getString("filename", "gradus.exr");
    Float scale = fp.getFloat("scale", 1);
    fp.getFloat("diagonal", 35);
    Float maxLum = fp.getFloat("maxsampleluminance", Infinity);
    if (std::isfinite(maxLum))
        throw UnsupportedError(fp.locOf("maxsampleluminance", fd.loc), "Film \"maxsampleluminance\" clamping");
    fp.checkUnused("Film \"image\"");
    if (!opts.outfileOverride.empty()) filename = opts.outfileOverride;
    if (opts.checkOutput) CheckWritableImagePath(filename);  // before any geometry is loaded or a sample rendered
    std::unique_ptr<Filter> filter = CreateFilter(desc.filter);
    try {
        job.film = std::make_unique<Film>(res, crop, std::move(filter), filename, scale);
    } catch (const Error &e) {  // a film too large for this machine: located at the resolution
        throw Error(fp.locOf("xresolution", fd.loc), e.what());
    }

    // Sampler.
    EntityDesc sdesc = desc.sampler;
    if (!sdesc.present) sdesc.type = "halton";
    int sppOverride = opts.sppOverride;
    job.sampler = CreateSampler(sdesc, opts.seed, sppOverride);
    if (opts.quick && sppOverride <= 0)
        job.sampler = CreateSampler(sdesc, opts.seed, std::max(1, job.sampler->samplesPerPixel() / 8));
    sdesc.params.checkUnused("Sampler \"" + sdesc.type + "\"");

    if (desc.accelerator.present) {
        // Embree replaces pbrt-v3's BVH/kd-tree; their tuning parameters are accepted and ignored.
        for (const auto &p : desc.accelerator.params.all()) p.used = true;
    }

    // Integrator.
    EntityDesc idesc = desc.integrator;
    if (!idesc.present) idesc.type = "path";
    bool overridden = !opts.integratorOverride.empty() && opts.integratorOverride != idesc.type;
    if (!opts.integratorOverride.empty()) idesc.type = opts.integratorOverride;
    MapPbrtSppm(&idesc);
    if (idesc.type == "volpath") idesc.type = "path";  // path renders media as pbrt-v3's volpath does
    ApplyParamOverrides(opts.paramOverrides, &idesc);
    job.integrator = CreateIntegrator(idesc);
    if (overridden) {
        // Parameters written for the scene's own integrator do not all apply to the override.
        for (const auto &p : idesc.params.all())
            if (!p.used) {
                job.warnings.push_back(p.loc.str() + ": parameter \"" + p.type + " " + p.name +
                                       "\" of Integrator \"" + desc.integrator.type + "\" is ignored by \"" +
                                       idesc.type + "\"");
                p.used = true;
            }
    }
    idesc.params.checkUnused("Integrator \"" + idesc.type + "\"");
    // Variance layers: --variance, or a gradient integrator's weighted reconstruction (which reads them).
    const Param *recon = idesc.params.find("reconstruction");
    job.film->setVarianceLayers(opts.variance || (recon && recon->strings.size() == 1 && recon->strings[0] == "weighted"));
    // An integrator with its own sample count (mlt's mutationsperpixel, vcm's
    // numiterations) keeps it unless --spp is given, carried by a "random" sampler
    // (a stratified one could round it; mlt draws no numbers from it, and pbrt-v3's
    // sppm ignores the scene's Sampler as well).
    if (const int n = job.integrator->defaultSamplesPerPixel(); n > 0 && sppOverride <= 0) {
        EntityDesc rd;
        rd.type = "random";
        rd.present = true;
        job.sampler = CreateSampler(rd, opts.seed, opts.quick ? std::max(1, n / 8) : n);
    }
    // pbrt-v3's integrator "pixelbounds": accepted when it covers the film, else
    // named as unsupported (never silently ignored).
    std::vector<int> pb = idesc.params.getInts("pixelbounds");
    if (!pb.empty()) {
        FileLoc at = idesc.params.locOf("pixelbounds", idesc.loc);
        if (pb.size() != 4) throw Error(at, "\"pixelbounds\" needs 4 values (x0 x1 y0 y1)");
        const Bounds2i &fb = job.film->pixelBounds();
        if (pb[0] > fb.pMin.x || pb[1] < fb.pMax.x || pb[2] > fb.pMin.y || pb[3] < fb.pMax.y)
            throw UnsupportedError(at, "Integrator \"pixelbounds\" that exclude film pixels (use --cropwindow)");
    }

    job.scene = BuildScene(desc, res);
    RefuseUnhandledParts(*job.integrator, *job.scene, desc, idesc);

    Metadata &m = job.provenance;
    auto entity = [](const EntityDesc &e, const std::string &type) {
        std::string r = e.params.resolved();
        return "\"" + type + "\"" + (r.empty() ? "" : " " + r);
    };
    m["camera"] = entity(desc.camera, desc.camera.present ? desc.camera.type : "perspective");
    m["sampler"] = entity(sdesc, sdesc.type);
    m["film"] = entity(fd, "image");
    m["pixelfilter"] = entity(desc.filter, desc.filter.present ? desc.filter.type : "box");
    m["integrator_parameters"] = entity(idesc, idesc.type);
    m["resolution"] = std::to_string(res.x) + "x" + std::to_string(res.y);
    m["cropwindow"] = std::to_string(crop[0]) + " " + std::to_string(crop[1]) + " " + std::to_string(crop[2]) +
                      " " + std::to_string(crop[3]);
    m["quick"] = MetaValue::Int(opts.quick ? 1 : 0);
    m["variance_layers"] = MetaValue::Int(job.film->varianceLayers() ? 1 : 0);
    InputFilesSummary in = InputFiles();
    m["scene_files"] = MetaValue::Int(in.files);
    m["scene_bytes"] = MetaValue::Int(int64_t(in.bytes));
    m["scene_hash"] = "fnv1a64:" + in.hash;
    return job;
}

std::string RenderIdentity(const RenderJob &job, const RenderOptions &opts) {
    // Everything the accumulated values depend on (not the output name, the
    // film's scale or the thread count).
    std::string id;
    for (const char *k : {"scene_hash", "camera", "sampler", "pixelfilter", "resolution", "cropwindow", "quick",
                          "integrator_parameters"}) {
        auto it = job.provenance.find(k);
        id += std::string(k) + ": " + (it == job.provenance.end() ? std::string("-") : it->second.str()) + "\n";
    }
    id += "integrator: " + job.integrator->name() + "\n";
    id += "spp: " + std::to_string(opts.spp) + " (" + std::to_string(opts.sppPerPass) + " per pass)\n";
    id += "seed: " + std::to_string(job.sampler->seed()) + "\n";
    if (job.film->varianceLayers()) id += "variance layers: yes\n";  // (absent in older checkpoints)
    return id;
}

namespace {
// The first line in which two identities differ, for the refusal message.
std::string FirstDifference(const std::string &a, const std::string &b) {
    std::istringstream sa(a), sb(b);
    std::string la, lb;
    while (true) {
        bool ga = bool(std::getline(sa, la)), gb = bool(std::getline(sb, lb));
        if (!ga && !gb) return "";
        if (!ga) la = "(none)";
        if (!gb) lb = "(none)";
        if (la != lb) return "checkpoint has \"" + la + "\", this render \"" + lb + "\"";
    }
}
}  // namespace

RenderResult RenderJobImage(RenderJob &job, const RenderOptions &opts) {
    using Clock = std::chrono::steady_clock;
    auto seconds = [](Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); };
    const double cpu0 = CpuSeconds();
    const auto t0 = Clock::now();
    job.integrator->preprocess(*job.scene, *job.film);
    const auto t1 = Clock::now();
    RenderOptions loopOpts = opts;
    if (opts.timeLimit > 0) {  // at least one pass runs whatever is left
        // The estimate may time a probe of its own: it is taken first, so that its
        // time counts as spent.
        const double finish = job.integrator->finishEstimate();
        loopOpts.timeLimit = std::max(1e-9, opts.timeLimit - seconds(t0, Clock::now()) - finish);
    }
    // Checkpoints: resume, --passes, periodic and final writes (render/checkpoint.h).
    const std::string identity = RenderIdentity(job, opts);
    Checkpoint prior;
    bool resumed = false;
    if (!opts.resumeFile.empty()) {
        if (opts.passBegin != 0 || opts.passEnd >= 0) throw Error("--resume and --passes exclude each other");
        prior = ReadCheckpoint(opts.resumeFile);
        if (prior.identity != identity || prior.integrator != job.integrator->name())
            throw Error(opts.resumeFile + ": a checkpoint of another render (" + FirstDifference(prior.identity, identity) +
                        "); resume with the scene, integrator, parameters, --spp and --seed it was made with");
        job.film->loadState(prior.film);
        try {
            job.integrator->loadState(prior.state);
        } catch (const Error &e) {
            throw Error(opts.resumeFile + ": " + e.what());
        }
        loopOpts.firstPass = prior.passEnd;
        loopOpts.firstSpp = prior.sppEnd;
        resumed = true;
    } else if (opts.passBegin != 0 || opts.passEnd >= 0) {
        if (opts.passBegin > 0 && !job.integrator->independentPasses())
            throw Error("--passes " + std::to_string(opts.passBegin) + ":...: " + job.integrator->name() +
                        "'s passes depend on the ones before (split it with --checkpoint and --resume instead)");
        if (opts.timeLimit > 0 && opts.spp <= 0) throw Error("--passes needs --spp (or the sampler's count), not --time alone");
        loopOpts.firstPass = opts.passBegin;
        loopOpts.firstSpp = -1;
        loopOpts.lastPass = opts.passEnd;
    }
    auto makeCheckpoint = [&](const RenderStats &st) {
        Checkpoint c;
        c.identity = identity;
        c.integrator = job.integrator->name();
        c.seed = job.sampler->seed();
        c.passBegin = resumed ? prior.passBegin : st.firstPass;
        c.sppBegin = resumed ? prior.sppBegin : st.firstSpp;
        c.passEnd = st.passes;
        c.sppEnd = st.spp;
        c.complete = st.complete;
        c.seconds = prior.seconds + seconds(t0, Clock::now());
        c.nonFinite = prior.nonFinite + st.nonFinite;
        c.film = job.film->saveState();
        c.state = job.integrator->saveState();
        return c;
    };
    auto lastWrite = Clock::now();
    double writeSeconds = 0;
    size_t writeBytes = 0;
    auto writeCheckpoint = [&](const RenderStats &st) {
        const auto w0 = Clock::now();
        Checkpoint c = makeCheckpoint(st);
        WriteCheckpoint(opts.checkpointFile, c);
        lastWrite = Clock::now();
        writeSeconds = seconds(w0, lastWrite);
        writeBytes = c.film.size() + c.state.size();
    };
    if (!opts.checkpointFile.empty()) {
        loopOpts.wholePasses = true;
        loopOpts.afterPass = [&](const RenderStats &st) {
            if (seconds(lastWrite, Clock::now()) >= opts.checkpointInterval) writeCheckpoint(st);
        };
    }
    RenderResult r;
    r.stats = RunRender(*job.integrator, *job.scene, *job.film, *job.sampler, loopOpts);
    if (!opts.checkpointFile.empty()) writeCheckpoint(r.stats);
    const auto t2 = Clock::now();
    r.image = job.film->toImage();
    job.integrator->finish(*job.film, r.stats, &r.image);
    const auto t3 = Clock::now();
    r.stats.seconds = seconds(t0, t3);

    const Film &film = *job.film;
    Metadata &m = r.image.metadata;
    for (const auto &kv : job.provenance) m[kv.first] = kv.second;
    m["integrator"] = job.integrator->name();
    m["spp"] = MetaValue::Int(r.stats.spp);
    m["passes"] = MetaValue::Int(r.stats.passes);
    m["seed"] = std::to_string(r.stats.seed);
    m["threads"] = MetaValue::Int(opts.nthreads > 0 ? opts.nthreads : int(std::thread::hardware_concurrency()));
    m["render_seconds"] = MetaValue::Double(r.stats.seconds);
    m["seconds_preprocess"] = MetaValue::Double(seconds(t0, t1));
    m["seconds_passes"] = MetaValue::Double(seconds(t1, t2));
    m["seconds_finish"] = MetaValue::Double(seconds(t2, t3));
    m["cpu_seconds"] = MetaValue::Double(CpuSeconds() - cpu0);
    m["stop_reason"] = r.stats.interrupted ? "interrupted" : r.stats.timeLimited ? "time budget" : "completed";
    if (opts.timeLimit > 0) m["time_budget"] = MetaValue::Double(opts.timeLimit);
    m["nonfinite_discarded"] = MetaValue::Int(int64_t(r.stats.nonFinite));
    m["output_values_clamped"] = MetaValue::Int(int64_t(film.clampedValues()));
    m["peak_rss_mb"] = MetaValue::Double(PeakRSSMegabytes());
    m["gradus_version"] = std::string(GradusVersion()) + " (" + GradusGitCommit() + ")";
    if (resumed) {
        m["resumed_from"] = opts.resumeFile;
        m["resumed_at_pass"] = MetaValue::Int(prior.passEnd);
        m["render_seconds_all_sessions"] = MetaValue::Double(prior.seconds + r.stats.seconds);
    }
    if (loopOpts.firstPass > 0 || loopOpts.lastPass >= 0) {
        m["pass_begin"] = MetaValue::Int(resumed ? prior.passBegin : r.stats.firstPass);
        m["pass_end"] = MetaValue::Int(r.stats.passes);
    }
    if (!opts.checkpointFile.empty()) {
        m["checkpoint"] = opts.checkpointFile;
        m["checkpoint_bytes"] = MetaValue::Int(int64_t(writeBytes));
        m["checkpoint_write_seconds"] = MetaValue::Double(writeSeconds);
    }
    // Crops keep their place in the full image (EXR data window in the display window).
    r.image.originX = film.pixelBounds().pMin.x;
    r.image.originY = film.pixelBounds().pMin.y;
    r.image.displayWidth = film.fullResolution().x;
    r.image.displayHeight = film.fullResolution().y;
    return r;
}

void ApplyParamOverrides(const std::vector<std::string> &overrides, EntityDesc *idesc) {
    if (overrides.empty()) return;
    const IntegratorInfo *info = nullptr;
    for (const auto &i : IntegratorRegistry())
        if (i.name == idesc->type) info = &i;
    if (!info) return;  // CreateIntegrator reports the unknown name
    const std::vector<ParamInfo> table = info->parameters();
    FileLoc loc;
    loc.file = std::make_shared<const std::string>("<command line --param>");
    for (const std::string &o : overrides) {
        size_t eq = o.find('=');
        std::string name = o.substr(0, eq);
        if (eq == std::string::npos || name.empty())
            throw Error(loc, "--param expects NAME=VALUE, got \"" + o + "\"");
        const ParamInfo *pi = nullptr;
        for (const auto &e : table)
            if (e.name == name) pi = &e;
        if (!pi)
            throw Error(loc, "integrator \"" + idesc->type + "\" has no parameter \"" + name +
                                 "\" (see gradus --describe " + idesc->type + ")");
        Param p;
        p.type = pi->typeName();
        p.name = name;
        p.loc = loc;
        std::string value = o.substr(eq + 1);
        if (p.type == "string") {
            p.strings.push_back(value);
        } else if (p.type == "bool") {
            if (value != "true" && value != "false")
                throw Error(loc, "--param " + name + " expects true or false, got \"" + value + "\"");
            p.bools.push_back(value == "true");
        } else {  // integer / float: one or more numbers separated by commas or spaces
            for (char &c : value)
                if (c == ',') c = ' ';
            std::istringstream in(value);
            std::string word;
            while (in >> word) {
                char *end = nullptr;
                double v = std::strtod(word.c_str(), &end);
                if (*end != 0 || !std::isfinite(v) || (p.type == "integer" && v != std::floor(v)))
                    throw Error(loc, "--param " + name + " expects " + p.type + " values, got \"" + word + "\"");
                p.numbers.push_back(v);
            }
            if (p.numbers.empty()) throw Error(loc, "--param " + name + " has no value");
        }
        idesc->params.add(std::move(p));
    }
}

}  // namespace gradus
