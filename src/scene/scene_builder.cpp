#include "scene/scene_builder.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/error.h"
#include "parser/ply.h"
#include "samplers/sampling.h"
#include "shapes/curve.h"
#include "shapes/heightfield.h"
#include "shapes/loopsubdiv.h"
#include "shapes/nurbs.h"
#include "shapes/quadrics.h"
#include "shapes/sphere.h"
#include "textures/textures.h"

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

// Embree traces in single precision and rejects ray origins beyond ~1.8e18:
// geometry (and anything rays would start from) must stay within 1e15 of the
// origin, or the renderer would abort inside Embree.
void CheckTraceableBounds(const Bounds3 &b, const FileLoc &loc) {
    constexpr Float kMax = 1e15;
    for (int i = 0; i < 3; ++i)
        if (!(std::abs(b.pMin[i]) <= kMax && std::abs(b.pMax[i]) <= kMax))
            throw Error(loc, "shape extends beyond 1e15 scene units from the origin (the range the ray tracer handles)");
}
// The stages of BuildScene, in the order that fixes geometry ids and the
// order of lights (images depend on both).
class SceneBuild {
  public:
    explicit SceneBuild(const SceneDesc &desc)
        : desc_(desc), scene_(std::make_unique<Scene>()), feat_(scene_->features) {}
    std::unique_ptr<Scene> build(Point2i resolution);

  private:
    struct ObjectBuild {
        int embreeObject = -1;
        std::vector<const Material *> materials;  // per mesh of the Embree object
        std::vector<MediumInterface> media;       // per mesh of the Embree object
        Bounds3 bounds;                           // of those meshes, in the object's space
        int64_t triangles = 0;
        std::vector<ShapeDesc> flattened;  // shapes copied per use
    };
    void buildMedia();
    void buildMaterials();
    void buildObjects();
    void addShape(const ShapeDesc &sd);
    void addAreaLights(const ShapeDesc &sd, const ShapeBuild &b, GeometryRecord *rec);
    void addInstances();
    void buildLights();
    void probeVisibleEmitters(Point2i resolution);
    const Medium *mediumNamed(const std::string &name);
    MediumInterface interfaceOf(const ShapeDesc &sd) {
        MediumInterface mi;
        mi.inside = mediumNamed(sd.insideMedium);
        mi.outside = mediumNamed(sd.outsideMedium);
        return mi;
    }
    const Material *materialOf(const ShapeDesc &sd);

    const SceneDesc &desc_;
    std::unique_ptr<Scene> scene_;
    SceneFeatures &feat_;
    std::map<std::string, const Medium *> mediumByName_;
    NamedTextures textures_;
    std::vector<const Material *> matByIndex_;
    std::shared_ptr<Material> defaultMaterial_;
    std::vector<ShapeDesc> shapes_;  // world shapes, then the flattened instance shapes
    std::map<std::string, ObjectBuild> objects_;
    std::vector<std::pair<const InstanceUseDesc *, const ObjectBuild *>> instanced_;
};

// Media (MakeNamedMedium); names were checked by the parser. "" is vacuum.
void SceneBuild::buildMedia() {
    for (const MediumDesc &md : desc_.media) {
        auto m = CreateMedium(md);
        md.params.checkUnused("MakeNamedMedium \"" + md.name + "\"");
        mediumByName_[md.name] = m.get();
        scene_->media.push_back(std::move(m));
    }
}

const Medium *SceneBuild::mediumNamed(const std::string &name) {
    if (name.empty()) return nullptr;
    feat_.media = true;
    return mediumByName_.at(name);
}

// Textures (in file order: later ones may reference earlier ones), then
// materials; "none"/"interface"/"" mean no surface (rays pass through).
void SceneBuild::buildMaterials() {
    for (const auto &td : desc_.textures) {
        CreateTexture(td, desc_, &textures_);
        td.params.checkUnused("Texture \"" + td.name + "\"");
        if (td.type != "constant") feat_.textures = true;
    }
    matByIndex_.assign(desc_.materials.size(), nullptr);
    std::map<std::string, std::shared_ptr<Material>> named;
    feat_.minRoughness = 1;
    for (size_t i = 0; i < desc_.materials.size(); ++i) {
        const MaterialDesc &md = desc_.materials[i];
        if (md.type.empty() || md.type == "none" || md.type == "interface") {
            md.params.checkUnused("Material \"" + md.type + "\"");
            continue;
        }
        auto m = CreateMaterial(md, textures_, named, &desc_, &scene_->notes);
        md.params.checkUnused("Material \"" + md.type + "\"");
        if (!md.name.empty()) named[md.name] = m;
        matByIndex_[i] = m.get();
        scene_->materials.push_back(m);
    }
    MaterialDesc defDesc;
    defDesc.type = "matte";
    defaultMaterial_ = CreateMaterial(defDesc, textures_, named);
    scene_->materials.push_back(defaultMaterial_);
}

const Material *SceneBuild::materialOf(const ShapeDesc &sd) {
    if (sd.material >= 0 && matByIndex_[sd.material]) {
        feat_.minRoughness = std::min(feat_.minRoughness, matByIndex_[sd.material]->minRoughness());
        if (matByIndex_[sd.material]->hasSubsurface()) feat_.subsurface = true;
    }
    return sd.material >= 0 ? matByIndex_[sd.material] : defaultMaterial_.get();
}

// Object instances. An object used more than once becomes an Embree instance:
// its triangle meshes are built and stored once, in the object's space, and
// every use adds only a transform (records with a MeshPlacement). Its analytic
// shapes and alpha-cut meshes, and objects used once, are flattened into world
// shapes (transformed copies).
void SceneBuild::buildObjects() {
    std::map<std::string, int> uses;
    for (const auto &use : desc_.instanceUses) {
        auto it = desc_.instances.find(use.name);
        if (it == desc_.instances.end()) throw Error(use.loc, "unknown object \"" + use.name + "\"");
        for (const ShapeDesc &s : it->second.shapes)
            if (s.areaLight >= 0) throw UnsupportedError(s.loc, "area lights inside object instances");
        ++uses[use.name];
    }
    auto flatten = [&](const std::vector<ShapeDesc> &objectShapes, const Transform &worldFromInstance) {
        for (ShapeDesc s : objectShapes) {
            s.worldFromObject = worldFromInstance * s.worldFromObject;
            shapes_.push_back(std::move(s));
        }
    };
    for (const auto &use : desc_.instanceUses) {
        const InstanceDesc &inst = desc_.instances.at(use.name);
        if (uses[use.name] == 1) {  // nothing to share
            flatten(inst.shapes, use.worldFromInstance);
            continue;
        }
        auto [found, isNew] = objects_.try_emplace(use.name);
        if (isNew) {
            ObjectBuild &ob = found->second;
            for (const ShapeDesc &sd : inst.shapes) {
                ShapeBuild b = CreateShape(sd, desc_, textures_);
                if (!b.mesh || b.mesh->alpha || b.mesh->shadowAlpha) {
                    ob.flattened.push_back(sd);
                    continue;
                }
                if (b.mesh->numTriangles() == 0) continue;
                if (b.subdivision) feat_.subdivisionSurfaces = true;
                if (ob.embreeObject < 0) ob.embreeObject = scene_->accel.newObject();
                for (const auto &q : b.mesh->p) ob.bounds.expand(q);
                ob.triangles += b.mesh->numTriangles();
                ob.materials.push_back(materialOf(sd));
                ob.media.push_back(interfaceOf(sd));
                scene_->accel.addObjectMesh(ob.embreeObject, b.mesh);
            }
            feat_.numStoredTriangles += ob.triangles;
        }
        const ObjectBuild &ob = found->second;
        if (ob.embreeObject >= 0) CheckTraceableBounds(use.worldFromInstance.applyBounds(ob.bounds), use.loc);
        flatten(ob.flattened, use.worldFromInstance);
        if (ob.embreeObject >= 0) instanced_.emplace_back(&use, &ob);
    }
}

// One world shape: its geometry record, area lights and accelerator geometry.
void SceneBuild::addShape(const ShapeDesc &sd) {
    ShapeBuild b = CreateShape(sd, desc_, textures_);
    GeometryRecord rec;
    rec.material = materialOf(sd);
    rec.mediumInterface = interfaceOf(sd);
    if (b.mesh) {
        if (b.mesh->numTriangles() == 0) return;  // empty mesh: nothing to add
        rec.mesh = b.mesh;
        feat_.numTriangles += b.mesh->numTriangles();
        feat_.numStoredTriangles += b.mesh->numTriangles();
        if (b.subdivision) feat_.subdivisionSurfaces = true;
        Bounds3 sb;
        for (const auto &p : b.mesh->p) sb.expand(p);
        CheckTraceableBounds(sb, sd.loc);
        scene_->bounds.expand(sb);
    } else if (b.curve) {
        rec.curve = b.curve;
        feat_.numCurveSegments += b.curve->numSegments();
        CheckTraceableBounds(b.curve->worldBound(), sd.loc);
        scene_->bounds.expand(b.curve->worldBound());
    } else {
        rec.analytic = b.analytic;
        rec.sphere = b.analytic;
        if (dynamic_cast<const Sphere *>(b.analytic.get())) feat_.numSpheres++;
        else feat_.numAnalytic++;
        CheckTraceableBounds(b.analytic->worldBound(), sd.loc);
        scene_->bounds.expand(b.analytic->worldBound());
    }
    if (sd.areaLight >= 0 && b.curve)  // pbrt-v3 allows it (rarely used); not supported here
        throw UnsupportedError(desc_.areaLights[sd.areaLight].loc, "an area light on a \"curve\" shape (made at " +
                                                                       sd.loc.str() + ")");
    if (sd.areaLight >= 0) addAreaLights(sd, b, &rec);
    int id = b.mesh    ? scene_->accel.addMesh(b.mesh)
             : b.curve ? scene_->accel.addCurve(b.curve)
                       : scene_->accel.addAnalytic(b.analytic);
    if (id != int(scene_->geometry.size())) throw Error("internal: geometry ids out of order");
    scene_->geometry.push_back(std::move(rec));
}

// AreaLightSource on a shape: one light per triangle (zero-area ones emit nothing).
void SceneBuild::addAreaLights(const ShapeDesc &sd, const ShapeBuild &b, GeometryRecord *rec) {
    const EntityDesc &ad = desc_.areaLights[sd.areaLight];
    if (ad.type != "diffuse" && ad.type != "area")
        throw Error(ad.loc, "unknown area light \"" + ad.type + "\" (valid: diffuse, area)");
    Spectrum L = ad.params.getSpectrum("L", Spectrum(1), SpectrumKind::Illuminant) *
                 ad.params.getSpectrum("scale", Spectrum(1));
    bool twoSided = ad.params.getBool("twosided", false);
    // Gradus extension (glTF emissive textures): "texture Lmap" scales L per
    // triangle by the texture's mean over the triangle (4x4 stratified
    // barycentric points): emission stays piecewise constant per triangle.
    std::shared_ptr<SpectrumTexture> lmap;
    if (ad.params.has("Lmap")) {
        std::string tn = ad.params.getTexture("Lmap");
        auto it = textures_.spectra.find(tn);
        if (tn.empty() || it == textures_.spectra.end())
            throw Error(ad.params.locOf("Lmap", ad.loc), "\"Lmap\": unknown spectrum texture \"" + tn + "\"");
        if (!b.mesh) throw UnsupportedError(ad.params.locOf("Lmap", ad.loc), "\"Lmap\" on non-triangle shapes");
        lmap = it->second;
    }
    // pbrt-v3's "samples" (alias "nsamples"): light samples per hit of directlighting's "all" strategy.
    const int nSamples = std::max(1, ad.params.getInt("samples", ad.params.getInt("nsamples", 1)));
    ad.params.checkUnused("AreaLightSource \"" + ad.type + "\"");
    auto addLight = [&](std::shared_ptr<AreaLight> al) {
        al->mediumInterface = rec->mediumInterface;
        al->nSamples = nSamples;
        rec->areaLights.push_back(al.get());
        scene_->lights.push_back(al);
    };
    if (b.mesh) {
        for (int t = 0; t < b.mesh->numTriangles(); ++t) {
            auto tri = std::make_shared<Triangle>(b.mesh, t);
            if (!(tri->area() > 0)) {  // zero-area triangles emit nothing
                rec->areaLights.push_back(nullptr);
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
                    rec->areaLights.push_back(nullptr);
                    continue;
                }
            }
            addLight(std::make_shared<AreaLight>(tri, Lt, twoSided));
        }
    } else if (b.analytic->area() > 0) {
        addLight(std::make_shared<AreaLight>(b.analytic, L, twoSided));
    } else {
        rec->areaLights.push_back(nullptr);
    }
    feat_.areaLights = true;
}

// Every use of a shared object: a placement and the object's meshes as records.
void SceneBuild::addInstances() {
    for (const auto &[use, ob] : instanced_) {
        scene_->bounds.expand(use->worldFromInstance.applyBounds(ob->bounds));
        scene_->placements.push_back(std::make_unique<MeshPlacement>(use->worldFromInstance));
        const MeshPlacement *pl = scene_->placements.back().get();
        const int first = scene_->accel.addInstance(ob->embreeObject, use->worldFromInstance);
        if (first != int(scene_->geometry.size())) throw Error("internal: geometry ids out of order");
        for (int k = 0; k < scene_->accel.objectMeshCount(ob->embreeObject); ++k) {
            GeometryRecord rec;
            rec.mesh = scene_->accel.objectMesh(ob->embreeObject, k);
            rec.placement = pl;
            rec.material = ob->materials[size_t(k)];
            rec.mediumInterface = ob->media[size_t(k)];
            scene_->geometry.push_back(std::move(rec));
        }
        feat_.numInstances++;
        feat_.numInstancedTriangles += ob->triangles;
        feat_.numTriangles += ob->triangles;
    }
}

// LightSource entities, then every light's preprocess with the scene bounds.
void SceneBuild::buildLights() {
    for (const auto &ld : desc_.lights) {
        auto l = CreateLight(ld, desc_);
        // Lights at a position sit in the medium current at LightSource;
        // lights at infinity send their light in from outside every medium.
        if (!(l->flags & (LIGHT_INFINITE | LIGHT_DELTA_DIRECTION))) {
            l->mediumInterface.inside = l->mediumInterface.outside = mediumNamed(ld.outsideMedium);
        }
        if (l->flags & LIGHT_INFINITE) {
            scene_->infiniteLights.push_back(l.get());
            feat_.infiniteLights = true;
        }
        if (IsDeltaLight(l->flags)) feat_.deltaLights = true;
        scene_->lights.push_back(l);
    }
    // Lights at infinity need the scene's bounding sphere (light-tracing
    // densities 1 / (pi r^2)); a world without shapes gets a unit box around
    // the camera instead of an empty one (r = 0 and a NaN centre made every
    // vcm sample non-finite: bench/stress empty_env).
    Bounds3 lightBounds = scene_->bounds;
    if (lightBounds.empty()) {
        const Point3 eye = desc_.camera.cameraFromWorld.inverse().applyPoint(Point3(0, 0, 0));
        const Point3 c = eye.isFinite() ? eye : Point3(0, 0, 0);
        lightBounds.expand(c - Vec3(1, 1, 1));
        lightBounds.expand(c + Vec3(1, 1, 1));
    }
    for (auto &l : scene_->lights) l->preprocess(lightBounds);
    feat_.numLights = int(scene_->lights.size());
}

// Are emitters directly visible? Probe a coarse grid of camera rays.
void SceneBuild::probeVisibleEmitters(Point2i resolution) {
    const int probe = 64;
    for (int y = 0; y < probe && !feat_.emittersDirectlyVisible; ++y)
        for (int x = 0; x < probe; ++x) {
            CameraSample cs;
            cs.pFilm = Point2((x + 0.5) * resolution.x / probe, (y + 0.5) * resolution.y / probe);
            cs.pLens = Point2(0.5, 0.5);
            Ray r;
            scene_->camera->generateRay(cs, &r);
            SurfaceInteraction si;
            bool hit = scene_->intersect(r, &si);
            if ((hit && si.areaLight) || (!hit && !scene_->infiniteLights.empty())) {
                feat_.emittersDirectlyVisible = true;
                break;
            }
        }
}

std::unique_ptr<Scene> SceneBuild::build(Point2i resolution) {
    // pbrt-v3 features that would otherwise be dropped silently.
    if (desc_.motionBlur)
        throw UnsupportedError(desc_.motionLoc, "motion blur (this entity's start and end transforms differ)");
    buildMedia();
    buildMaterials();
    shapes_ = desc_.shapes;
    buildObjects();
    for (const auto &sd : shapes_) addShape(sd);
    addInstances();
    scene_->accel.commit();
    if (!scene_->bounds.empty()) {
        Point3 c;
        Float r;
        scene_->bounds.boundingSphere(&c, &r);
        gRayEpsilon = 1e-6 * std::min<Float>(1, std::max<Float>(r, 1e-6));
    }
    buildLights();
    feat_.specularSurfaces = feat_.minRoughness == 0;
    feat_.nearSpecularSurfaces = feat_.minRoughness < kDefaultShiftThreshold;
    scene_->camera = CreateCamera(desc_.camera, resolution, &desc_);
    scene_->cameraMedium = mediumNamed(desc_.camera.mediumName);
    probeVisibleEmitters(resolution);
    return std::move(scene_);
}

}  // namespace

std::unique_ptr<Scene> BuildScene(const SceneDesc &desc, Point2i resolution) {
    return SceneBuild(desc).build(resolution);
}

}  // namespace gradus
