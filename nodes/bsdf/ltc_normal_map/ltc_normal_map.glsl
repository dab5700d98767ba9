// bsdf.ltc_normal_map: the GLSL twin of the node's CPU path (ltc_normal_map.node.cpp) and of
// ltc::NormalMapLtcPrefilter::lookup (core/ltc/ltc_prefilter.cpp): per footprint and view a specular and a diffuse LTC.
//
// Design after ltc-filtering.md §4-5 (Nahmias 2022): hardware trilinear over texels and MIP levels of the stored
// levels (resource 'tables', a 2D array whose GL level g is prefilter level g + 1, LTCs premultiplied by their
// magnitude so GL_LINEAR computes the CPU's magnitude-weighted sum), software bilinear over the (θ, φ) view grid
// (a layer triple per view), and for footprints finer than one texel the per-texel base GGX LTCs (MIP 0, from
// 'normals' and the base tables) blended with level 1, as the CPU does. Then the lobes: direction queries
// f·cos = tint·magnitude·D_ltc(wi) (ltc::LtcLobe::evalPdf), polygon queries tint·magnitude·∫_P D_ltc
// (ltc::LtcLobe::integratePolygon, shared/ltc.glsl).

// The view grids of ltc::PrefilterSettings (the node always fits with the defaults; the layer count of 'tables' is
// 3·(8·16 + 2·4) = 408) and the θ range of the grid (thesis §3.4.1: the last view stops at 0.999·π/2).
const int SPC_LNM_SPEC_THETA = 8;
const int SPC_LNM_SPEC_PHI = 16;
const int SPC_LNM_DIFF_THETA = 2;
const int SPC_LNM_DIFF_PHI = 4;
const float SPC_LNM_THETA_MAX = 1.5692255304681018;
const float SPC_LNM_TWO_PI = 6.283185307179586;

// (mag, fres) of the isotropic base table for α at cos θ (the amplitude half of ltc::ggxIsotropic).
vec2 spc_lnm_mag_fres(sampler2D ltc_amplitude, float alpha, float cosTheta) {
    cosTheta = clamp(cosTheta, 0.0, 1.0);
    vec2 uv = vec2(spc_ltc_coord(sqrt(clamp(alpha, 0.0, 1.0))), spc_ltc_coord(sqrt(1.0 - cosTheta)));
    return texture(ltc_amplitude, uv).xy;  // GL_LINEAR + CLAMP_TO_EDGE = ltc::sampleBilinear
}

// The θ of view row j of n (NormalMapLtcPrefilter viewTheta).
float spc_lnm_view_theta(int j, int n) { return n > 1 ? float(j) / float(n - 1) * SPC_LNM_THETA_MAX : 0.0; }

// Per-row factors (mag j0, mag j1, fres j0, fres j1) of the specular θ interpolation: the flat surface's magnitude
// and Fresnel moment at θ over those at the two rows (NormalMapLtcPrefilter::thetaScales).
vec4 spc_lnm_theta_scales(sampler2D ltc_amplitude, float alpha, float theta) {
    vec4 sc = vec4(1.0);
    const int nt = SPC_LNM_SPEC_THETA;
    float tt = min(max(theta / SPC_LNM_THETA_MAX * float(nt - 1), 0.0), float(nt - 1));
    int j0 = min(int(floor(tt)), nt - 2);
    vec2 at = spc_lnm_mag_fres(ltc_amplitude, alpha, cos(theta));
    for (int r = 0; r < 2; ++r) {
        vec2 node = spc_lnm_mag_fres(ltc_amplitude, alpha, cos(spc_lnm_view_theta(j0 + r, nt)));
        if (node.x > 1e-4) sc[r] = at.x / node.x;
        if (node.y > 1e-4) sc[2 + r] = at.y / node.y;
    }
    return sc;
}

// One layer of 'tables' at (uv, lod): GL's trilinear filter (GL_LINEAR_MIPMAP_LINEAR, REPEAT), which is the CPU's
// bilinear-per-level and linear-between-levels filter with texel centres at (i + 1/2)/n (lookupLevel).
vec4 spc_lnm_fetch(sampler2DArray tables, vec2 uv, float lod, int layer) {
    return textureLod(tables, vec3(uv, float(layer)), lod);
}

// Adds w·(mag·inv(M), mag, fres) of the stored LTCs of one lobe at (uv, lod), interpolated over the 2×2 nearest
// views (θ linear and clamped, φ linear and wrapping), into a0 = m[0..3], a1 = m[4..7], a2 = (m[8], mag, fres)
// (NormalMapLtcPrefilter::accumulateStored; the texel and level weights are the hardware filter's here).
void spc_lnm_stored(sampler2DArray tables, vec2 uv, float lod, float theta, float phi, float w, bool diffuse,
                    vec4 sc, inout vec4 a0, inout vec4 a1, inout vec3 a2) {
    int nt = diffuse ? SPC_LNM_DIFF_THETA : SPC_LNM_SPEC_THETA, np = diffuse ? SPC_LNM_DIFF_PHI : SPC_LNM_SPEC_PHI;
    int base = diffuse ? 3 * SPC_LNM_SPEC_THETA * SPC_LNM_SPEC_PHI : 0;
    float tt = nt > 1 ? theta / SPC_LNM_THETA_MAX * float(nt - 1) : 0.0;
    tt = min(max(tt, 0.0), float(nt - 1));
    int j0 = min(int(floor(tt)), max(nt - 2, 0));
    float ft = nt > 1 ? tt - float(j0) : 0.0;
    float tp = phi / SPC_LNM_TWO_PI * float(np);
    float fp0 = floor(tp);
    float fp = tp - fp0;
    int k0 = max(int(fp0), 0) % np, k1 = (k0 + 1) % np;  // phi in [0, 2π]: fp0 >= 0
    int j1 = min(j0 + 1, nt - 1);
    int views[4] = int[4](j0 * np + k0, j0 * np + k1, j1 * np + k0, j1 * np + k1);
    int rows[4] = int[4](0, 0, 1, 1);
    float ew[4] = float[4]((1.0 - ft) * (1.0 - fp), (1.0 - ft) * fp, ft * (1.0 - fp), ft * fp);
    for (int e = 0; e < 4; ++e) {
        float ww = w * ew[e];
        if (ww == 0.0) continue;
        float sm = diffuse ? 1.0 : sc[rows[e]], sf = diffuse ? 1.0 : sc[2 + rows[e]];
        int layer = base + 3 * views[e];
        vec4 t0 = spc_lnm_fetch(tables, uv, lod, layer);
        vec4 t1 = spc_lnm_fetch(tables, uv, lod, layer + 1);
        vec4 t2 = spc_lnm_fetch(tables, uv, lod, layer + 2);
        float wm = ww * sm;
        a0 += wm * t0;
        a1 += wm * t1;
        a2 += vec3(wm * t2.x, wm * t2.y, ww * sf * t2.z);
    }
}

// The texel-frame rotation R0 (columns t, b, n: the minimal rotation z -> n, NormalMapLtcPrefilter::texelRotation).
mat3 spc_lnm_texel_rotation(vec3 n) {
    float a = 1.0 / (1.0 + n.z);
    vec3 t = vec3(1.0 - n.x * n.x * a, -n.x * n.y * a, -n.x);
    vec3 b = vec3(-n.x * n.y * a, 1.0 - n.y * n.y * a, -n.y);
    return mat3(t, b, n);
}

float spc_lnm_frobenius(mat3 m) { return sqrt(dot(m[0], m[0]) + dot(m[1], m[1]) + dot(m[2], m[2])); }

mat3 spc_lnm_matrix(vec4 a0, vec4 a1, float a8) { return mat3(a0.xyz, vec3(a0.w, a1.xy), vec3(a1.zw, a8)); }

// The footprint's LTCs in the geometric tangent frame (NormalMapLtcPrefilter::lookup): invM, magnitude and Fresnel
// moment of the specular lobe, invM and magnitude of the diffuse lobe. wo: unit, geometric tangent frame.
void spc_lnm_lookup(sampler2DArray tables, sampler2D normals, sampler2D ltc_matrix, sampler2D ltc_amplitude, float alpha,
                    vec2 uv, vec2 duvdx, vec2 duvdy, vec3 wo, out mat3 specInv, out vec2 specMagFres,
                    out mat3 diffInv, out float diffMag) {
    specInv = mat3(1.0);
    diffInv = mat3(1.0);
    specMagFres = vec2(0.0);
    diffMag = 0.0;
    int size = textureSize(normals, 0).x;
    if (!(wo.z > 0.0) || size < 1) return;
    int levels = findMSB(size);
    // θ and φ from a float-accurate two-argument arctangent (shared/ltc.glsl), not acos(wo.z) / atan(y, x): GLSL sets
    // no precision for them and llvmpipe's are short polynomials: direction parity 2.2e-3 with acos, 2.6e-5 with
    // atan, 5.4e-6 with this (tests/glsl/test_glsl_parity.cpp).
    float theta = spc_ltc_angle(length(wo.xy), wo.z);
    float phi = wo.y >= 0.0 ? spc_ltc_angle(wo.y, wo.x) : SPC_LNM_TWO_PI - spc_ltc_angle(-wo.y, wo.x);
    if (any(isinf(uv)) || any(isnan(uv))) uv = vec2(0.0);
    // The MIP level: GL's ρ (the longer footprint axis in texels of the map), as the CPU computes it.
    float rho = max(length(duvdx), length(duvdy)) * float(size);
    float level = rho > 0.0 ? log2(rho) : 0.0;
    if (!(level > 0.0)) level = 0.0;
    level = min(level, float(levels));
    // Geometric-frame sums of the MIP-0 part (g*) and view-aligned sums of the stored levels (v*).
    mat3 gs = mat3(0.0), gd = mat3(0.0);
    vec2 gsMagFres = vec2(0.0);
    float gdMag = 0.0;
    vec4 s0 = vec4(0.0), s1 = vec4(0.0), d0 = vec4(0.0), d1 = vec4(0.0);
    vec3 s2 = vec3(0.0), d2 = vec3(0.0);
    vec4 sc = spc_lnm_theta_scales(ltc_amplitude, alpha, theta);
    if (level >= 1.0) {
        // Stored levels only: one trilinear fetch per layer (GL level = prefilter level − 1).
        spc_lnm_stored(tables, uv, level - 1.0, theta, phi, 1.0, false, sc, s0, s1, s2);
        spc_lnm_stored(tables, uv, level - 1.0, theta, phi, 1.0, true, sc, d0, d1, d2);
    } else {
        float f = levels > 0 ? level : 0.0;
        if (f > 0.0) {
            spc_lnm_stored(tables, uv, 0.0, theta, phi, f, false, sc, s0, s1, s2);
            spc_lnm_stored(tables, uv, 0.0, theta, phi, f, true, sc, d0, d1, d2);
        }
        // MIP 0: bilinear over the base LTCs of the 4 nearest texels (repeat wrap, centres at (i + 1/2)/size).
        float wl = 1.0 - f;
        float sx = uv.x * float(size) - 0.5, sy = uv.y * float(size) - 0.5;
        float fx0 = floor(sx), fy0 = floor(sy);
        float ax = sx - fx0, ay = sy - fy0;
        int ix = int(fx0), iy = int(fy0);
        for (int c = 0; c < 4; ++c) {
            int dx = c & 1, dy = c >> 1;
            float w = wl * (dx != 0 ? ax : 1.0 - ax) * (dy != 0 ? ay : 1.0 - ay);
            if (w == 0.0) continue;
            int x = (ix + dx) & (size - 1), y = (iy + dy) & (size - 1);  // repeat; GLSL's % is undefined below 0
            vec3 n = texelFetch(normals, ivec2(x, y), 0).xyz;
            mat3 Rt = transpose(spc_lnm_texel_rotation(n));
            vec3 woT = Rt * wo;
            if (!(woT.z > 1e-6)) continue;  // the texel faces away: no light towards wo (as in the fit)
            mat3 b;
            vec2 mf;
            spc_ltc_ggx_isotropic(ltc_matrix, ltc_amplitude, max(alpha, 1e-3), woT, b, mf);
            if (mf.x > 0.0) {
                mat3 m = b * Rt;  // geometric direction -> texel frame -> cosine space
                gs += m * (w * mf.x / spc_lnm_frobenius(m));
                gsMagFres += w * mf;
            }
            gd += Rt * (w / sqrt(3.0));  // the cosine lobe about the texel normal; a rotation has norm √3
            gdMag += w;
        }
    }
    // Back from the view-aligned frame: invM (geometric) = invM_view · Rz(−φ), plus the MIP-0 part.
    float c = cos(phi), s = sin(phi);
    mat3 back = mat3(1.0);
    back[0][0] = c;
    back[1][0] = s;
    back[0][1] = -s;
    back[1][1] = c;
    mat3 ms = spc_lnm_matrix(s0, s1, s2.x) * back + gs;
    specMagFres = gsMagFres + s2.yz;
    if (spc_lnm_frobenius(ms) > 0.0 && specMagFres.x > 0.0) specInv = ms;
    mat3 md = spc_lnm_matrix(d0, d1, d2.x) * back + gd;
    diffMag = gdMag + d2.y;
    if (spc_lnm_frobenius(md) > 0.0 && diffMag > 0.0) diffInv = md;
}

// D(w) of an LTC for a unit w (ltc::Ltc::density, HDHN16 Eq. 1).
float spc_lnm_density(mat3 invM, vec3 w) {
    vec3 o = invM * w;
    float l2 = dot(o, o);
    if (!(l2 > 0.0)) return 0.0;
    float l = sqrt(l2);
    float cosO = o.z / l;
    if (cosO <= 0.0) return 0.0;
    return cosO * SPC_INV_PI * abs(determinant(invM)) / (l2 * l);
}

void spc_bsdf_ltc_normal_map(SpeculaClosureQuery q, int convention, float roughness, float strength,
                             vec3 specular_color, vec3 diffuse_color, vec2 uv, vec2 duvdx, vec2 duvdy, vec3 normal,
                             vec3 tangent, float sign_, sampler2DArray tables, sampler2D normals, sampler2D ltc_matrix,
                             sampler2D ltc_amplitude, out SpeculaClosure bsdf) {
    bsdf = spc_closure_none();
    // convention and strength are already in 'normals' and 'tables' (prepared on the CPU); roughness gives α of the
    // MIP-0 base LTCs and of the θ ratio scales, clamped as the CPU clamps it (the tables were fitted for it).
    float r = min(max(roughness, 0.0316), 1.0);
    float alpha = max(r * r, 1e-3);
    // The geometric tangent frame (T, N×T, N), right-handed; for sign < 0 the map's +v is −(N×T): wo mirrored in y
    // for the lookup, the LTCs mirrored back (S invM S, S = diag(1, −1, 1)), as the CPU does.
    vec3 T, B, N;
    spc_frame(normal, tangent, T, B, N);
    vec3 o = spc_to_local(q.wo, T, B, N);
    bool mirror = sign_ < 0.0;
    vec3 ol = o;
    if (mirror) ol.y = -ol.y;
    mat3 specInv, diffInv;
    vec2 magFres;
    float diffMag;
    spc_lnm_lookup(tables, normals, ltc_matrix, ltc_amplitude, alpha, uv, duvdx, duvdy, ol, specInv, magFres, diffInv,
                   diffMag);
    if (mirror) {
        mat3 S = mat3(1.0);
        S[1][1] = -1.0;
        specInv = S * specInv * S;
        diffInv = S * diffInv * S;
    }
    // Schlick through the LTC moments (HDHN16 §4): ∫ F f·cos = F0·mag + (1 − F0)·fres; the diffuse gets what the
    // specular does not reflect, per channel.
    float mag = magFres.x;
    vec3 specAlbedo = clamp(specular_color * mag + (vec3(1.0) - specular_color) * magFres.y, vec3(0.0), vec3(1.0));
    vec3 specTint = mag > 0.0 ? specAlbedo / mag : vec3(0.0);
    vec3 diffTint = diffuse_color * (vec3(1.0) - specAlbedo);
    if (o.z <= 0.0) return;  // also what the lobes answer for a view below the surface
    if (q.kind != SPC_QUERY_DIRECTION) {  // polygon and environment queries
        vec3 p[4];
        spc_ltc_local_polygon(q, T, B, N, p);
        bool env = q.kind == SPC_QUERY_ENVIRONMENT;
        if (mag > 0.0)
            bsdf.f += specTint * (mag * spc_ltc_integrate(specInv, p, q.vertex_count, q.horizon, ltc_amplitude)) *
                      (env ? spc_ltc_environment(specInv, T, B, N) : vec3(1.0));
        if (diffMag > 0.0)
            bsdf.f_diffuse = diffTint * (diffMag * spc_ltc_integrate(diffInv, p, q.vertex_count, q.horizon, ltc_amplitude)) *
                             (env ? spc_ltc_environment(diffInv, T, B, N) : vec3(1.0));
        bsdf.f += bsdf.f_diffuse;
        return;
    }
    vec3 i = spc_to_local(q.wi, T, B, N);
    if (i.z <= 0.0) return;
    if (mag > 0.0) bsdf.f += specTint * (mag * spc_lnm_density(specInv, i));
    if (diffMag > 0.0) bsdf.f_diffuse = diffTint * (diffMag * spc_lnm_density(diffInv, i));
    bsdf.f += bsdf.f_diffuse;
}
