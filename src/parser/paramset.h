// Parameter lists of scene directives ("float fov" [45] ...). Every parameter
// remembers where it came from and whether it was looked up; after building an
// entity, the scene builder calls checkUnused(), which throws a located error
// for the first parameter nobody asked for (misspelt or unsupported).
#pragma once
#include <initializer_list>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/geometry.h"
#include "core/spectrum.h"
#include "parser/spectrum_convert.h"

namespace gradus {

struct Param {
    std::string type;  // as written: integer, float, point2, point3, vector3, normal, rgb, ...
    std::string name;
    FileLoc loc;       // location of the "type name" string
    std::vector<double> numbers;       // numeric types (rgb/color/spectrum already as numbers)
    std::vector<std::string> strings;  // string, texture, spectrum given as filename/named
    std::vector<bool> bools;
    mutable bool used = false;
};

class ParamSet {
  public:
    // Adds a parameter; a later one with the same name replaces the earlier one.
    void add(Param p);
    bool has(const std::string &name) const { return find(name) != nullptr; }
    // Finds a parameter by name (any type) and marks it used; nullptr if absent.
    const Param *find(const std::string &name) const;
    const std::vector<Param> &all() const { return params_; }

    // Typed lookups. A parameter present with the wrong type or the wrong
    // number of values throws a located Error. Each marks the parameter used.
    int getInt(const std::string &name, int def) const;
    Float getFloat(const std::string &name, Float def) const;
    bool getBool(const std::string &name, bool def) const;
    std::string getString(const std::string &name, const std::string &def) const;
    Point2 getPoint2(const std::string &name, Point2 def) const;
    Point3 getPoint3(const std::string &name, Point3 def) const;  // point/point3
    Vec3 getVector3(const std::string &name, Vec3 def) const;     // vector/vector3
    Normal3 getNormal(const std::string &name, Normal3 def) const;
    // rgb / color / spectrum (inline pairs, named or .spd file) / blackbody, as linear RGB.
    // Sampled spectra ("spectrum" pairs or .spd files) are converted as
    // reflectances (a constant spectrum c gives grey c); use the overload with
    // SpectrumKind::Illuminant for emission. blackbody is always an illuminant.
    Spectrum getSpectrum(const std::string &name, Spectrum def) const;
    Spectrum getSpectrum(const std::string &name, Spectrum def, SpectrumKind kind) const;
    // Name of a texture parameter ("texture Kd" "mytex"), or "" if absent.
    std::string getTexture(const std::string &name) const;

    std::vector<int> getInts(const std::string &name) const;
    std::vector<Float> getFloats(const std::string &name) const;
    std::vector<Point2> getPoint2s(const std::string &name) const;  // point2, or float pairs for "uv"/"st"
    std::vector<Point3> getPoint3s(const std::string &name) const;
    std::vector<Normal3> getNormals(const std::string &name) const;
    std::vector<Vec3> getVector3s(const std::string &name) const;
    std::vector<std::string> getStrings(const std::string &name) const;

    // Location of a parameter (for errors about its value); `fallback` if absent.
    FileLoc locOf(const std::string &name, const FileLoc &fallback) const;
    // Throws Error at the first parameter never looked up:
    // "file:l:c: parameter "float fvo" is not used by Camera "perspective" (misspelt or unsupported)".
    void checkUnused(const std::string &what) const;

    // The values every scalar lookup returned, given or default, in lookup order,
    // in scene-file syntax ("integer maxdepth" 5 "string strategy" "power" ...):
    // the resolved parameters recorded in the outputs' metadata.
    std::string resolved() const;

    // Canonical spelling of a parameter type: point->point3, vector->vector3,
    // normal->normal3, color->rgb; other names unchanged.
    static std::string canonicalType(const std::string &type);

  private:
    // Finds `name`, checks its canonical type is one of `types` (else throws a
    // located error naming `expected`), marks it used.
    const Param *lookup(const std::string &name, std::initializer_list<const char *> types,
                        const char *expected) const;
    int getIntRaw(const std::string &name, int def) const;
    Float getFloatRaw(const std::string &name, Float def) const;
    bool getBoolRaw(const std::string &name, bool def) const;
    std::string getStringRaw(const std::string &name, const std::string &def) const;
    Point2 getPoint2Raw(const std::string &name, Point2 def) const;
    Point3 getPoint3Raw(const std::string &name, Point3 def) const;
    Vec3 getVector3Raw(const std::string &name, Vec3 def) const;
    Normal3 getNormalRaw(const std::string &name, Normal3 def) const;
    Spectrum getSpectrumRaw(const std::string &name, Spectrum def, SpectrumKind kind) const;
    std::vector<int> getIntsRaw(const std::string &name) const;
    std::vector<Float> getFloatsRaw(const std::string &name) const;
    std::vector<std::string> getStringsRaw(const std::string &name) const;
    void note(const char *type, const std::string &name, const std::string &value) const;
    std::vector<Param> params_;
    mutable std::vector<std::pair<std::string, std::string>> resolved_;  // name, text
};

}  // namespace gradus
