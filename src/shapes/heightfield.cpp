#include "shapes/heightfield.h"

#include <cmath>

namespace gradus {

MeshData HeightfieldMesh(int nu, int nv, const std::vector<Float> &Pz) {
    GRADUS_CHECK(nu >= 2 && nv >= 2 && Pz.size() == size_t(nu) * size_t(nv));
    MeshData m;
    m.P.reserve(Pz.size());
    m.uv.reserve(Pz.size());
    for (int y = 0; y < nv; ++y)
        for (int x = 0; x < nu; ++x) {
            Float u = Float(x) / (nu - 1), v = Float(y) / (nv - 1);
            m.P.push_back(Point3(u, v, Pz[x + size_t(y) * nu]));
            m.uv.push_back(Point2(u, v));
        }
    auto vert = [nu](int x, int y) { return x + y * nu; };
    m.indices.reserve(6 * size_t(nu - 1) * (nv - 1));
    for (int y = 0; y + 1 < nv; ++y)
        for (int x = 0; x + 1 < nu; ++x) {
            for (int i : {vert(x, y), vert(x + 1, y), vert(x + 1, y + 1)}) m.indices.push_back(i);
            for (int i : {vert(x, y), vert(x + 1, y + 1), vert(x, y + 1)}) m.indices.push_back(i);
        }
    return m;
}

MeshData CreateHeightfield(const ParamSet &ps, const FileLoc &loc) {
    const int nu = ps.getInt("nu", -1), nv = ps.getInt("nv", -1);
    if (nu < 2) throw Error(ps.locOf("nu", loc), "heightfield: \"integer nu\" must be given and >= 2");
    if (nv < 2) throw Error(ps.locOf("nv", loc), "heightfield: \"integer nv\" must be given and >= 2");
    std::vector<Float> Pz = ps.getFloats("Pz");
    // 64-bit product: nu * nv may overflow int for absurd inputs.
    const long long want = (long long)nu * nv;
    if ((long long)Pz.size() != want)
        throw Error(ps.locOf("Pz", loc), "heightfield: \"float Pz\" has " + std::to_string(Pz.size()) +
                                             " values, nu * nv = " + std::to_string(want) + " needed");
    for (size_t i = 0; i < Pz.size(); ++i)
        if (!std::isfinite(Pz[i]))
            throw Error(ps.locOf("Pz", loc), "heightfield: \"Pz\" value " + std::to_string(i) + " is not finite");
    return HeightfieldMesh(nu, nv, Pz);
}

}  // namespace gradus
