// Compact connection records for integrators that connect a camera subpath
// with light subpaths stored elsewhere (M-BDPT's matrix connections): the
// connection (s, t), s >= 2, t >= 2, reads the light endpoint q_{s-1} from one
// 128-byte record (two cache lines) instead of walking the light subpath and
// its arena BSDF.
//
// A record holds the vertex (position, normals, wo, throughput), the BSDF's
// parameters when the material is compact (Lambertian reflection: f = R / pi
// and the cosine density), and the light side of the MIS sum in VCM's
// recursive form (Georgiev et al. 2012, "Light transport simulation with
// vertex connection and merging", Sec. 4 and its technical report's
// recursive MIS quantities, as vcm/ keeps them; connections only: Veach 1997
// Eq. 10.9 with the ratios below the endpoint's predecessor accumulated
// along the subpath).
// Other materials and medium vertices are "Stored": the connection evaluates
// their BSDF / phase function and pdfs from the store's vertex with the exact
// functions of bidir.h, but still takes the MIS sum from the record.
//
// MIS (bidir.h OtherStrategies, notation rho_j = remap(pdfRev_j) / remap(pdfFwd_j),
// mis(x) = x (balance) or x^2 (power), remap(0) = 1): for the light subpath
// L[0..], with A_i = [L[i-1] not delta (i = 0: L[0] not a delta light) and the
// edge L[i-1]--L[i] connectible] and A'_i = A_i [L[i] not delta],
//   S_k = mis(rho_k) (A'_k + S_{k-1}),  S_{-1} = 0,
// the light terms of strategy (s, t) are
//   mis(a1) (A_{s-1} + mis(a2) (A'_{s-2} + S_{s-3})),
// a1 = remap(p(q_{s-1} from p_{t-1})) / remap(pdfFwd_{s-1}),
// a2 = remap(p(q_{s-2} from q_{s-1})) / remap(pdfFwd_{s-2}) (the two reverse
// densities that depend on the camera subpath). The camera side is the same
// with B_i (i = 1: the light-tracing strategy, weighted by n_LT, and left out
// for rays through the filter margin) and T_k = mis(rho_k) (B'_k n_k + T_{k-1}),
// T_0 = 0 (CameraSums). The weight is 1 / (1 + camera terms + light terms):
// the same sums as MISWeight, added in another order (equal up to rounding;
// tests/mbdpt test_records.cpp compares them on random paths).
#pragma once
#include <cstdint>
#include <vector>

#include "integrators/common/bidir.h"

namespace gradus {

enum class RecordKind : uint8_t {
    None,        // not a connection endpoint (light origin, specular, camera-only vertex types)
    Lambertian,  // compact: f = fR, cosine-weighted density, evaluated from the record
    Stored,      // BSDF / phase function of the store's vertex (and its predecessor)
};

struct alignas(64) LightRecord {
    Point3 p;
    PackedVec3 ng, ns, wo;
    float beta[3];           // throughput, times 2^(-8 betaExp) (PathVertex)
    union {
        float fR[3];         // Lambertian: R / pi (the BxDF's value)
        uint32_t vertex;     // Stored: index of the vertex in the store
    };
    int32_t geomId;          // medium of a connecting ray (MediumTowards)
    Float fwd;               // remap(pdfFwd) of this vertex
    Float fwdPrev;           // remap(pdfFwd) of the previous vertex
    Float revPrev;           // Lambertian: area density of the previous vertex sampled from this
                             // one (PdfArea), when the hemisphere test passes
    Float tail;              // A'_{k-1} + S_{k-2} (mis applied)
    int8_t betaExp;
    VertexType type;
    uint8_t flags;
    RecordKind kind;
    uint8_t mediumIndex;
    uint8_t endAllowed;      // A_k
    int8_t prevSide;         // Lambertian: sign of the local z of the direction to the previous vertex
    int8_t woSide;           // Lambertian: sign of the local z of wo
};
static_assert(sizeof(LightRecord) == 128, "a light record is two cache lines");

// Records of the vertices of one light subpath (with its BSDFs; bsdf may be
// nullptr only for subpaths without surface vertices beyond the origin).
// rec[i] describes L[i] as the endpoint q_{s-1} of strategy s = i + 1;
// firstIndex: index of L[0] in the store (for Stored records).
void BuildLightRecords(const BidirContext &ctx, SubpathView light, uint32_t firstIndex, LightRecord *rec);

// Camera side of the MIS sums of one camera subpath: for vertex i >= 1,
// end[i] = n_i B_i, in[i] = n_i B'_i and T[i] (see above), T[0] = 0.
struct CameraSums {
    std::vector<Float> end, in, T;
    void build(const BidirContext &ctx, SubpathView camera);
};

// Strategy (s, t), s >= 2, t >= 2, of the camera subpath with the light
// endpoint `rec` (and, for Stored records, the store's vertex `stored`,
// stored[-1] its predecessor, and its BSDF `storedBsdf`): ConnectBDPT's
// result, with the weight from the sums. u: rng and knownVisible.
bool ConnectRecord(const BidirContext &ctx, const LightRecord &rec, const PathVertex *stored,
                   const BSDF *storedBsdf, const CameraSums &cam, SubpathView camera, int s, int t,
                   const ConnectSamples &u, ConnectResult *res);

// Next-event estimation through the matrix (strategy s = 1, t >= 2): camera
// vertex t - 1 connected to `origin`, the emitter vertex L[0] of a light
// subpath of another pixel, instead of a point sampled from the camera vertex.
// With y0's density p(y0) = pmf(light) p_pos(y0) (its pdfFwd: the density the
// MIS sums give strategy s = 1 in pbrt-v3's BDPT and here):
//   area light:      f = beta_t f_t(y0) Le(y0 -> x_t) |cos_y0| |cos_t| / (|y0 - x_t|^2 p(y0)),
//   delta position:  f = beta_t f_t(y0) I(y0 -> x_t) |cos_t| / (|y0 - x_t|^2 p(y0))
// (Veach 1997 Eq. 10.8 with the stored origin as the light subpath's only
// vertex). Weight: the camera sums and, on the light side, strategy (0, t + 1)
// alone, mis(p(y0 from x_t) / p(y0)) [y0 not a delta light] (Eq. 10.9).
// Infinite and distant lights are not connectible origins here (false).
bool ConnectLightOrigin(const BidirContext &ctx, const PathVertex &origin, const CameraSums &cam,
                        SubpathView camera, int t, const ConnectSamples &u, ConnectResult *res);
// True when `v` (a light subpath's vertex 0) can be the origin of ConnectLightOrigin.
inline bool IsMatrixLightOrigin(const PathVertex &v) {
    return v.type == VertexType::Light && !v.isInfiniteLight() && IsConnectible(v, nullptr);
}

}  // namespace gradus
