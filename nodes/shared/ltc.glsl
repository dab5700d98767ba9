// Shared GLSL library of the LTC lobes (NodeSpec::glslLibraries "shared/ltc.glsl"): polygon integrals of linearly
// transformed cosines with exact horizon clipping or the clip-free sphere approximation, and the GGX table lookups.
//
// GLSL twin of core/ltc/ltc.cpp (integrate, clampedCosineIntegral), core/ltc/ltc_tables.cpp (ggxIsotropic,
// ggxAnisotropic, sphereScale) and core/ltc/ltc_ggx.cpp (ggxRoughnessMatrix, fresnelScale); math in
// shared/specs/ltc-filtering.md §1-3 (HDHN16 = Heitz, Dupuy, Hill & Neubelt 2016). The tables are the BuiltinTable
// resources of core/ltc/ltc_gpu.h (ltc_matrix, ltc_amplitude, ltc_anisotropic), passed in as sampler2D parameters.
// The CPU integrates in double; here everything is float, so the formulas are chosen to stay well conditioned.

const float SPC_LTC_INV_2PI = 0.15915494309189533577;

// The angle in [0, π] of the point (x, y), y >= 0, to float precision. GLSL's atan has no precision requirement and
// llvmpipe's is a short polynomial whose error the cancelling edge sums amplify: with atan(y, x) the exact-clip
// polygon integrals differed from the CPU's (double) by up to 7e-4 relative (test_glsl_ltc), with this one by 4e-5.
// Octant reduction to t in [0, 1], t' = (t − 1)/(t + 1) with +π/4 for t > tan(π/8), then the Taylor series of atan
// on |t'| <= tan(π/8) to degree 21 (truncation < 1e-9).
float spc_ltc_angle(float y, float x) {
    float ax = abs(x);
    bool swap = y > ax;
    float t = swap ? ax / y : (ax > 0.0 ? y / ax : 0.0);
    float off = 0.0;
    if (t > 0.41421356) {
        t = (t - 1.0) / (t + 1.0);
        off = 0.78539816339744831;
    }
    float t2 = t * t;
    float p = -1.0 / 21.0;
    p = p * t2 + 1.0 / 19.0;
    p = p * t2 - 1.0 / 17.0;
    p = p * t2 + 1.0 / 15.0;
    p = p * t2 - 1.0 / 13.0;
    p = p * t2 + 1.0 / 11.0;
    p = p * t2 - 1.0 / 9.0;
    p = p * t2 + 1.0 / 7.0;
    p = p * t2 - 1.0 / 5.0;
    p = p * t2 + 1.0 / 3.0;
    float r = off + (t - t * t2 * p);
    if (swap) r = 1.5707963267948966 - r;
    return x < 0.0 ? 3.14159265358979324 - r : r;
}

// One edge term of Lambert's form factor for unit a, b (HDHN16 Eq. 11, ltc-filtering.md §3 step 2):
// θ·[(a×b)/|a×b|]_z / 2π. θ from (|a×b|, a·b) instead of the CPU's acos(a·b): in float, acos of a dot product
// near 1 loses all relative precision (short edges), the two-argument form keeps it for every angle.
float spc_ltc_edge_exact(vec3 a, vec3 b) {
    vec3 c = cross(a, b);
    float s = length(c);
    if (!(s > 0.0)) return 0.0;  // coincident (or antipodal) vertices: no edge
    return spc_ltc_angle(s, dot(a, b)) * (c.z / s) * SPC_LTC_INV_2PI;
}

// The edge's contribution to the form-factor vector for unit a, b (ltc::edgeVectorRational): (a×b)·θ/sin θ/2π with
// x = a·b = cos θ and ltc_code's rational fit of θ/sin θ/2π (§3 step 3), using θ/sin θ = π/sin θ − θ'/sin θ'
// (θ' = π − θ) for x < 0. There sin²θ is taken as |a×b|², not 1 − x² as on the CPU: equal for unit vectors, but in
// float 1 − x² cancels for nearly opposite vertices (wide edges of grazing GGX lobes in cosine space).
vec3 spc_ltc_edge_vector(vec3 a, vec3 b) {
    vec3 c = cross(a, b);
    float x = dot(a, b), y = abs(x);
    float v = (0.8543985 + (0.4965155 + 0.0145206 * y) * y) / (3.4175940 + (4.1616724 + y) * y);
    return c * (x >= 0.0 ? v : 0.5 / sqrt(max(dot(c, c), 1e-7)) - v);
}

// Sutherland-Hodgman clip of a polygon of n <= 4 vertices against the half-space z > 0 of cosine space (§3 step 4,
// ltc::clipToUpperHemisphere): at most 5 vertices out; the new vertices lie exactly on z = 0.
int spc_ltc_clip(vec3 v[4], int n, out vec3 c[5]) {
    for (int k = 0; k < 5; ++k) c[k] = vec3(0.0);
    int m = 0;
    for (int i = 0; i < 4; ++i) {
        if (i >= n) break;
        vec3 p = v[i], q = v[(i + 1) % n];
        bool pIn = p.z > 0.0, qIn = q.z > 0.0;
        if (pIn) c[m++] = p;
        if (pIn != qIn) {
            vec3 x = p + (p.z / (p.z - q.z)) * (q - p);
            x.z = 0.0;
            c[m++] = x;
        }
    }
    return m;
}

// ltc_code's LUT_SCALE/LUT_BIAS for the 64-texel axes: node coordinate c in [0, 1] -> c·63/64 + 0.5/64, written as
// the CPU's lutCoord computes it ((c·63)/64, then the bias) so both round alike.
float spc_ltc_coord(float c) { return c * 63.0 / 64.0 + 0.5 / 64.0; }

// scale(z, len) of the clip-free path (§3 step 5, ltc::sphereScale): ltc_amplitude.w, GL_LINEAR + CLAMP_TO_EDGE,
// which is what ltc::sampleBilinear reproduces on the CPU.
float spc_ltc_sphere_scale(sampler2D ltc_amplitude, float z, float len) {
    vec2 uv = vec2(spc_ltc_coord(clamp(0.5 * z + 0.5, 0.0, 1.0)), spc_ltc_coord(clamp(len, 0.0, 1.0)));
    return texture(ltc_amplitude, uv).w;
}

// ∫_P D_o over a polygon already in cosine space (vertices relative to the shading point, any length,
// counter-clockwise seen from the origin when it faces it), one-sided (ltc::clampedCosineIntegral, twoSided false).
// horizon SPC_HORIZON_CLIP: clip, normalise, exact edges, max(0, E). SPC_HORIZON_CLIPLESS: the unclipped form-factor
// vector F from the rational edges, 0 when the polygon is seen from behind, else |F|·scale(F_z/|F|, |F|).
float spc_ltc_cosine_integral(vec3 v[4], int n, int horizon, sampler2D ltc_amplitude) {
    if (n < 3 || n > 4) return 0.0;
    if (horizon != SPC_HORIZON_CLIPLESS) {
        vec3 c[5];
        int m = spc_ltc_clip(v, n, c);
        if (m < 3) return 0.0;
        for (int k = 0; k < 5; ++k)
            if (k < m) c[k] = normalize(c[k]);
        float e = 0.0;
        for (int k = 0; k < 5; ++k)
            if (k < m) e += spc_ltc_edge_exact(c[k], c[(k + 1) % m]);
        return max(0.0, e);
    }
    vec3 u[4];
    for (int k = 0; k < 4; ++k) u[k] = k < n ? normalize(v[k]) : vec3(0.0, 0.0, 1.0);
    vec3 F = vec3(0.0), nrm = vec3(0.0), ctr = vec3(0.0);
    for (int k = 0; k < 4; ++k) {
        if (k >= n) break;
        F += spc_ltc_edge_vector(u[k], u[(k + 1) % n]);
        nrm += cross(v[k], v[(k + 1) % n]);  // Newell normal: which side of the polygon the origin sees
        ctr += v[k];
    }
    if (dot(nrm, ctr) < 0.0) return 0.0;  // seen from behind: a one-sided light gives nothing
    float len = length(F);
    if (!(len > 0.0)) return 0.0;
    float z = clamp(F.z / len, -1.0, 1.0);
    return len * spc_ltc_sphere_scale(ltc_amplitude, z, len);
}

// ∫_P D over a polygon in the LTC's lobe frame (ltc::integrate): transform by invM; a reflection in invM reverses the
// winding, so the vertex order is reversed to keep the sign convention in cosine space.
float spc_ltc_integrate(mat3 invM, vec3 p[4], int n, int horizon, sampler2D ltc_amplitude) {
    bool flip = determinant(invM) < 0.0;
    vec3 v[4];
    for (int k = 0; k < 4; ++k) v[k] = vec3(0.0);
    for (int k = 0; k < 4; ++k)
        if (k < n) v[flip ? n - 1 - k : k] = invM * p[k];
    return spc_ltc_cosine_integral(v, n, horizon, ltc_amplitude);
}

// The polygon of a query in a lobe frame (T, B, N): world-space offsets rotated into it (Closure::integratePolygon).
void spc_ltc_local_polygon(SpeculaClosureQuery q, vec3 T, vec3 B, vec3 N, out vec3 p[4]) {
    for (int k = 0; k < 4; ++k) p[k] = spc_to_local(q.polygon[k], T, B, N);
}

// Isotropic GGX LTC (ltc::ggxIsotropic): inv(M) of the view-aligned frame from ltc_matrix, bilinear in
// (√α, √(1 − cos θ)) (§2 "Grid"), rows (x, 0, z), (0, 1, 0), (y, 0, w), with the lobe -> view rotation (rows T1, T2, N,
// §3 step 1) folded in; magFres = (mag, fres) from ltc_amplitude.xy.
void spc_ltc_ggx_isotropic(sampler2D ltc_matrix, sampler2D ltc_amplitude, float alpha, vec3 wo, out mat3 invM,
                           out vec2 magFres) {
    float cosTheta = clamp(wo.z, 0.0, 1.0);
    vec2 uv = vec2(spc_ltc_coord(sqrt(clamp(alpha, 0.0, 1.0))), spc_ltc_coord(sqrt(1.0 - cosTheta)));
    vec4 m = texture(ltc_matrix, uv);
    magFres = texture(ltc_amplitude, uv).xy;
    mat3 inv = mat3(0.0);
    inv[0][0] = m.x;
    inv[0][2] = m.y;
    inv[1][1] = 1.0;
    inv[2][0] = m.z;
    inv[2][2] = m.w;
    vec3 t1 = vec3(wo.x, wo.y, 0.0);
    float l = sqrt(t1.x * t1.x + t1.y * t1.y);
    t1 = l > 1e-7 ? t1 / l : vec3(1.0, 0.0, 0.0);  // wo along the normal: any T1
    vec3 t2 = vec3(-t1.y, t1.x, 0.0);              // N × T1 with N = z
    invM = inv * transpose(mat3(t1, t2, vec3(0.0, 0.0, 1.0)));
}

// Anisotropic GGX LTC (ltc::ggxAnisotropic): wo mirrored into the first quadrant (the lobe is symmetric under
// x -> −x and y -> −y), quadrilinear interpolation of the 16 corner cells of ltc_anisotropic read with texelFetch in
// the CPU's corner order (so the sums round alike), then mirrored back: invM = F·inv·S with S = diag(sx, sy, 1) and
// F = diag(1, sx·sy, 1) (a cosine-space y flip that keeps det invM > 0; the clamped cosine is symmetric in y).
void spc_ltc_ggx_anisotropic(sampler2D ltc_anisotropic, float alphaX, float alphaY, vec3 wo, out mat3 invM,
                             out vec2 magFres) {
    ivec2 size = textureSize(ltc_anisotropic, 0);  // (3·n², n·nφ), core/ltc/ltc_gpu.h
    int n = int(sqrt(float(size.x / 3)) + 0.5);
    int np = size.y / n;
    float sx = wo.x < 0.0 ? -1.0 : 1.0, sy = wo.y < 0.0 ? -1.0 : 1.0;
    float cosTheta = clamp(wo.z, 0.0, 1.0);
    float phi = spc_ltc_angle(abs(wo.y), abs(wo.x));  // atan2, accurate (see spc_ltc_angle)
    float c[4];
    c[0] = sqrt(clamp(alphaX, 0.0, 1.0)) * float(n - 1);
    c[1] = sqrt(clamp(alphaY, 0.0, 1.0)) * float(n - 1);
    c[2] = sqrt(1.0 - cosTheta) * float(n - 1);
    c[3] = np > 1 ? phi / (0.5 * SPC_PI) * float(np - 1) : 0.0;
    int dims[4] = int[4](n, n, n, np);
    int i0[4];
    float f[4];
    for (int d = 0; d < 4; ++d) {
        float x = clamp(c[d], 0.0, float(dims[d] - 1));
        i0[d] = min(int(x), max(dims[d] - 2, 0));
        f[d] = dims[d] > 1 ? x - float(i0[d]) : 0.0;
    }
    vec4 a0 = vec4(0.0), a1 = vec4(0.0), a2 = vec4(0.0);
    for (int corner = 0; corner < 16; ++corner) {
        float w = 1.0;
        int idx[4];
        for (int d = 0; d < 4; ++d) {
            int b = (corner >> d) & 1;
            idx[d] = min(i0[d] + b, dims[d] - 1);
            w *= b != 0 ? f[d] : 1.0 - f[d];
        }
        if (w == 0.0) continue;
        int x = 3 * (idx[1] * n + idx[0]), y = idx[3] * n + idx[2];
        a0 += w * texelFetch(ltc_anisotropic, ivec2(x, y), 0);
        a1 += w * texelFetch(ltc_anisotropic, ivec2(x + 1, y), 0);
        a2 += w * texelFetch(ltc_anisotropic, ivec2(x + 2, y), 0);
    }
    mat3 inv = mat3(a0.xyz, vec3(a0.w, a1.xy), vec3(a1.zw, a2.x));  // glm/GLSL column-major, entries 0..8
    magFres = a2.yz;
    mat3 S = mat3(1.0), F = mat3(1.0);
    S[0][0] = sx;
    S[1][1] = sy;
    F[1][1] = sx * sy;
    invM = F * inv * S;
}

// The LTC of GGX with the roughness matrix A = [[a, c], [c, d]] given as vec3(a, c, d) (ltc::ggxRoughnessMatrix):
// eigenvalues λ1 >= λ2 of A; (nearly) isotropic -> the 64×64 table with α = (√λ1 + √λ2)/2; axis-aligned -> the
// anisotropic table with (√a, √d); otherwise the principal frame at φ0 = ½ atan2(2c, a − d), rotation folded in.
void spc_ltc_ggx_matrix(sampler2D ltc_matrix, sampler2D ltc_amplitude, sampler2D ltc_anisotropic, vec3 A, vec3 wo,
                        out mat3 invM, out vec2 magFres) {
    float a = A.x, c = A.y, d = A.z;
    float h = 0.5 * (a + d), g = sqrt(max(0.0, 0.25 * (a - d) * (a - d) + c * c));
    // λ2 = det A / λ1 rather than h − g: in float the difference cancels for strongly anisotropic A (relative error
    // ~1e-7·λ1/λ2), the quotient does not (the CPU subtracts in double).
    float l1 = max(h + g, 0.0);
    float ax = sqrt(l1), ay = l1 > 0.0 ? sqrt(max(a * d - c * c, 0.0) / l1) : 0.0;
    if (abs(ax - ay) <= 1e-4 * ax) {
        spc_ltc_ggx_isotropic(ltc_matrix, ltc_amplitude, 0.5 * (ax + ay), wo, invM, magFres);
        return;
    }
    if (abs(c) < 1e-12 * max(a, d)) {  // already axis-aligned: no rotation
        spc_ltc_ggx_anisotropic(ltc_anisotropic, sqrt(max(a, 0.0)), sqrt(max(d, 0.0)), wo, invM, magFres);
        return;
    }
    // (cos φ0, sin φ0) for φ0 = ½ atan2(2c, a − d) in (−π/2, π/2] without trigonometry (whose GL implementations
    // carry ~1e-6 errors): cos 2φ0 = (a − d)/2g, sin 2φ0 = c/g and the half-angle formulas, each branch on the side
    // where it does not cancel.
    float c2 = 0.5 * (a - d) / g, s2 = c / g;
    float cs, sn;
    if (c2 >= 0.0) {
        cs = sqrt(0.5 * (1.0 + c2));
        sn = s2 / (2.0 * cs);
    } else {
        sn = (c < 0.0 ? -1.0 : 1.0) * sqrt(0.5 * (1.0 - c2));
        cs = s2 / (2.0 * sn);
    }
    mat3 R = mat3(1.0);  // rows (cs, sn, 0), (−sn, cs, 0), (0, 0, 1): lobe frame -> principal frame
    R[0][0] = cs;
    R[1][0] = sn;
    R[0][1] = -sn;
    R[1][1] = cs;
    spc_ltc_ggx_anisotropic(ltc_anisotropic, ax, ay, R * wo, invM, magFres);
    invM = invM * R;
}

// An axis-aligned GGX (αx along x, αy along y): ggxRoughnessMatrix(αx², 0, αy²) with the roots taken exactly (the CPU
// squares and roots in double, which returns αx and αy unchanged).
void spc_ltc_ggx_axes(sampler2D ltc_matrix, sampler2D ltc_amplitude, sampler2D ltc_anisotropic, float alphaX,
                      float alphaY, vec3 wo, out mat3 invM, out vec2 magFres) {
    float hi = max(alphaX, alphaY), lo = min(alphaX, alphaY);
    if (abs(hi - lo) <= 1e-4 * hi)
        spc_ltc_ggx_isotropic(ltc_matrix, ltc_amplitude, 0.5 * (hi + lo), wo, invM, magFres);
    else
        spc_ltc_ggx_anisotropic(ltc_anisotropic, alphaX, alphaY, wo, invM, magFres);
}

// The Schlick-equivalent reflectance of an LTC integral, F0·mag + (1 − F0)·fres with F0 = F(1) (ltc::fresnelScale,
// ltc-filtering.md §2 "Magnitude and Fresnel"); F0 = 1 (no Fresnel) gives mag exactly.
// Environment queries (SPC_QUERY_ENVIRONMENT): the host's prefiltered radiance where an LTC lobe of frame (T, B, N)
// points (ltc::environmentLookup): the direction M·ẑ normalised and α = 1/(2 |det M⁻¹|^½ |M ẑ|^{3/2}) in [0, 1], the
// GGX roughness whose reflected lobe has the LTC's peak density.
vec3 spc_ltc_environment(mat3 invM, vec3 T, vec3 B, vec3 N) {
    vec3 m = inverse(invM)[2];
    float len = length(m), det = abs(determinant(invM));
    if (!(len > 0.0) || !(det > 0.0)) return spc_host_environment(N, 1.0);
    vec3 d = m / len;
    float alpha = clamp(0.5 / (sqrt(det) * len * sqrt(len)), 0.0, 1.0);
    return spc_host_environment(T * d.x + B * d.y + N * d.z, alpha);
}
vec3 spc_ltc_fresnel_scale(vec3 F0, vec2 magFres) { return F0 * magFres.x + (vec3(1.0) - F0) * magFres.y; }

// The fitted GGX LTC of (αx, αy) for the local view lo integrated over the query's polygon, without Fresnel (CPU:
// ltc::GgxPolygonLobe::integratePolygon); invM and magFres come back for the Fresnel weighting (spc_ltc_fresnel_scale)
// and the environment lookup (spc_ltc_environment). Shared by bsdf.ggx and bsdf.dielectric.
float spc_ltc_ggx_polygon(SpeculaClosureQuery q, sampler2D ltc_matrix, sampler2D ltc_amplitude, sampler2D ltc_anisotropic,
                          float ax, float ay, vec3 lo, vec3 T, vec3 B, vec3 N, out mat3 invM, out vec2 magFres) {
    spc_ltc_ggx_axes(ltc_matrix, ltc_amplitude, ltc_anisotropic, ax, ay, lo, invM, magFres);
    vec3 p[4];
    spc_ltc_local_polygon(q, T, B, N, p);
    return spc_ltc_integrate(invM, p, q.vertex_count, q.horizon, ltc_amplitude);
}
