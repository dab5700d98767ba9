// Texels and sampler state of the LTC tables for the GPU (ltc_gpu.h): repacks ltc::builtinTables() into the RGBA32F
// layouts nodes/shared/ltc.glsl reads, so the GLSL lookups reproduce ltc::ggxIsotropic/ggxAnisotropic/sphereScale.
#include "nodes/shared/ltc_gpu.h"

#include "core/ltc/ltc_tables.h"

namespace specula::ltc {

namespace {
graph::ResourceImage image(int w, int h, std::vector<float> rgba, bool linear) {
    graph::ResourceImage r;
    graph::ResourceImage::Level lv;
    lv.width = w;
    lv.height = h;
    lv.rgba = std::move(rgba);
    r.levels.push_back(std::move(lv));
    // No MIP chain: the lookups sample level 0 only (texture() of a MIP-less texture with a non-mipmap min filter).
    r.minFilter = r.magFilter = linear ? "linear" : "nearest";
    r.wrapS = r.wrapT = "clamp_to_edge";
    return r;
}
}  // namespace

graph::ResourceImage matrixImage(const void*) {
    const LtcTables& t = builtinTables();
    const int n = LtcTables::kIsoSize;
    return image(n, n, t.ggxInv, true);  // already (x = a, y = t) rows, 4 floats per texel
}

graph::ResourceImage amplitudeImage(const void*) {
    const LtcTables& t = builtinTables();
    const int n = LtcTables::kIsoSize;
    std::vector<float> px(size_t(n) * n * 4, 0.f);
    for (size_t c = 0; c < size_t(n) * n; ++c) {
        px[c * 4 + 0] = t.ggxMagFres[c * 2 + 0];
        px[c * 4 + 1] = t.ggxMagFres[c * 2 + 1];
        px[c * 4 + 3] = t.sphere[c];
    }
    return image(n, n, std::move(px), true);
}

graph::ResourceImage anisotropicImage(const void*) {
    const LtcTables& t = builtinTables();
    const int n = t.anisoSize, np = t.anisoPhiSize;
    const int w = 3 * n * n, h = n * np;
    std::vector<float> px(size_t(w) * h * 4, 0.f);
    for (int k = 0; k < np; ++k)
        for (int th = 0; th < n; ++th)
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    size_t cell = ((size_t(k) * n + th) * n + j) * n + i;
                    float* p = &px[(size_t(k * n + th) * w + size_t(3 * (j * n + i))) * 4];
                    for (int e = 0; e < 9; ++e) p[e] = t.anisoInv[cell * 9 + e];
                    p[9] = t.anisoMagFres[cell * 2 + 0];
                    p[10] = t.anisoMagFres[cell * 2 + 1];
                }
    return image(w, h, std::move(px), false);
}

graph::ResourceSpec matrixResource() {
    return {"ltc_matrix", "sampler2D", graph::ResourceSpec::Kind::BuiltinTable,
            "LTC isotropic GGX inverse matrices (HDHN16, Nelder-Mead fit): 64x64 RGBA32F, texel (roughness index, "
            "view index) = inv(M) entries (0,0), (2,0), (0,2), (2,2); linear, clamp_to_edge",
            &matrixImage};
}

graph::ResourceSpec amplitudeResource() {
    return {"ltc_amplitude", "sampler2D", graph::ResourceSpec::Kind::BuiltinTable,
            "LTC magnitude, Fresnel and sphere tables: 64x64 RGBA32F (mag, fres, 0, clip-free horizon scale(z, |F|)); "
            "linear, clamp_to_edge",
            &amplitudeImage};
}

graph::ResourceSpec anisotropicResource() {
    return {"ltc_anisotropic", "sampler2D", graph::ResourceSpec::Kind::BuiltinTable,
            "LTC anisotropic GGX (t-EM fit, 8^4 cells over alpha_x, alpha_y, theta, phi): 192x64 RGBA32F, 3 texels per "
            "cell (9 inv(M) entries, mag, fres); nearest, clamp_to_edge, interpolated in the shader with texelFetch",
            &anisotropicImage};
}

}  // namespace specula::ltc
