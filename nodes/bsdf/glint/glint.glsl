// bsdf.glint: f.cos of the procedural glint BRDF (C20) with GGAA and slope correlation (C21), the GLSL twin of
// nodes/bsdf/glint/glint_bsdf.h and the headers it includes (same operations, spec glint-brdf.md §3 S0-S7).
// The dictionary is the node's resource 'dictionary' (a sampler1DArray parameter; the emitter declares and binds it and
// lists its texels and sampler state in the module's resource manifest): RGBA32F, width 64, 1024 layers, our exact box
// MIP chain 0..6, trilinear, mirrored repeat on s (C21 supplemental). Layer = k*64 + d/3, channel = d%3 (C20/C21
// layout). Without GGAA the level-0 table is read with textureLod.

const float SPC_GLINT_SIGMA_O = 0.35355339059327373;
const float SPC_GLINT_LIM = 1.4142135623730951;  // 4 sigma_o

// Non-axis-aligned Beckmann SDF P_B (spec S7).
float spc_glint_beckmann(vec2 h, float sx, float sy, float rho, float sq) {
    float a = h.x / sx, b = h.y / sy;
    float q = (a * a - 2.0 * rho * a * b + b * b) / (sq * sq);
    return exp(-0.5 * q) / (2.0 * SPC_PI * sx * sy * sq);
}

// Hugo-Elias hash (Quilez), clamped to [2^-24, 1 - 2^-24] (spec S4.2).
float spc_glint_hash(uint n) {
    n = (n << 13u) ^ n;
    n = n * (n * n * 15731u + 789221u) + 1376312589u;
    float u = float(n & 0x7fffffffu) / 2147483647.0;
    return clamp(u, 5.9604645e-8, 0.99999994);
}

// Giles (2010) single-precision erfinv.
float spc_glint_erfinv(float x) {
    float w = -log((1.0 - x) * (1.0 + x)), p;
    if (w < 5.0) {
        w = w - 2.5;
        p = 2.81022636e-08;
        p = 3.43273939e-07 + p * w;
        p = -3.5233877e-06 + p * w;
        p = -4.39150654e-06 + p * w;
        p = 0.00021858087 + p * w;
        p = -0.00125372503 + p * w;
        p = -0.00417768164 + p * w;
        p = 0.246640727 + p * w;
        p = 1.50140941 + p * w;
    } else {
        w = sqrt(w) - 3.0;
        p = -0.000200214257;
        p = 0.000100950558 + p * w;
        p = 0.00134934322 + p * w;
        p = -0.00367342844 + p * w;
        p = 0.00573950773 + p * w;
        p = -0.0076224613 + p * w;
        p = 0.00943887047 + p * w;
        p = 1.00167406 + p * w;
        p = 2.83297682 + p * w;
    }
    return p * x;
}

// One marginal d of dictionary level k at u (texture units), unfiltered or with the GGAA gradients (S5.4). The MIP
// level is GL's isotropic rule mu = log2(64 max(|g1|, |g2|)) computed here exactly, as textureGrad1D does on the CPU:
// textureGrad would leave it to the implementation, whose LOD approximation (llvmpipe's, a vendor's) shifts the blend
// between two MIPs by up to a tenth of the value.
float spc_glint_marginal(sampler1DArray dictionary, int k, int d, float u, bool ggaa, float g1, float g2) {
    vec2 tc = vec2(u, float(k * 64 + d / 3));
    float rho = 64.0 * max(abs(g1), abs(g2));
    float lod = (ggaa && rho > 1.0) ? min(log2(rho), 6.0) : 0.0;
    vec4 t = textureLod(dictionary, tc, lod);
    int ch = d - 3 * (d / 3);
    return ch == 0 ? t.x : (ch == 1 ? t.y : t.z);
}

struct SpcGlintQuery {
    float sx, sy, rho, sq, detMinv;
    float relArea, jitter, lcBase;
    vec2 mh;
    bool ggaa;
    vec2 gx, gy;
    float pB;
};

// S4 + S5: SDF of cell (s, t) at level l.
float spc_glint_cell(sampler1DArray dictionary, SpcGlintQuery q, int l, int s, int t) {
    uint p = 1u << uint(l);
    uint S = uint(s) * p + 1549u * uint(t) * p;
    float uA = spc_glint_hash(13u * S), uZ = spc_glint_hash(2171u * S), uT = spc_glint_hash(S);
    float uI = spc_glint_hash(16807u * S), uJ = spc_glint_hash(48271u * S);
    if (uA > q.relArea) return 0.0;
    float lc = q.lcBase + float(l);
    float ld = lc + q.jitter * 1.41421356 * spc_glint_erfinv(2.0 * uZ - 1.0);
    int k = int(clamp(floor(ld + 0.5), 0.0, 16.0));
    if (k == 16) return q.pB;
    float theta = 2.0 * SPC_PI * uT;
    float c = cos(theta), sn = sin(theta);
    float mx = c * q.mh.x + sn * q.mh.y, my = -sn * q.mh.x + c * q.mh.y;
    if (abs(mx) >= SPC_GLINT_LIM || abs(my) >= SPC_GLINT_LIM) return 0.0;
    int i = min(int(192.0 * uI), 191), j = min(int(192.0 * uJ), 191);
    float ux = abs(mx) / SPC_GLINT_LIM, uy = abs(my) / SPC_GLINT_LIM;
    float gxx = c * q.gx.x + sn * q.gx.y, gxy = -sn * q.gx.x + c * q.gx.y;
    float gyx = c * q.gy.x + sn * q.gy.y, gyy = -sn * q.gy.x + c * q.gy.y;
    float px = spc_glint_marginal(dictionary, k, i, ux, q.ggaa, gxx, gyx);
    float py = spc_glint_marginal(dictionary, k, j, uy, q.ggaa, gxy, gyy);
    return q.detMinv * px * py;
}

// S3: EWA weights over the cells of level l (cap: 100 cells).
float spc_glint_level(sampler1DArray dictionary, SpcGlintQuery q, int l, vec2 uv, vec2 a1, vec2 a2) {
    float n = float(1 << (15 - l));
    float cs = uv.x * n - 0.5, ct = uv.y * n - 0.5;
    vec2 b1 = a1 * n, b2 = a2 * n;
    float A = b1.y * b1.y + b2.y * b2.y + 1.0;
    float B = -2.0 * (b1.x * b1.y + b2.x * b2.y);
    float C = b1.x * b1.x + b2.x * b2.x + 1.0;
    float F = A * C - B * B * 0.25;
    A /= F;
    B /= F;
    C /= F;
    float det = 4.0 * A * C - B * B;
    float invDet = 1.0 / det;
    float su = 2.0 * invDet * sqrt(det * C), sv = 2.0 * invDet * sqrt(det * A);
    int s0 = int(ceil(cs - su)), s1 = int(floor(cs + su));
    int t0 = int(ceil(ct - sv)), t1 = int(floor(ct + sv));
    float sumW = 0.0, sumWP = 0.0;
    int count = 0;
    for (int t = t0; t <= t1 && count < 100; ++t) {
        float dt = float(t) - ct;
        for (int s = s0; s <= s1; ++s) {
            float ds = float(s) - cs;
            float r2 = A * ds * ds + B * ds * dt + C * dt * dt;
            if (!(r2 < 1.0)) continue;
            if (count >= 100) break;
            ++count;
            float W = exp(-2.0 * r2) - 0.13533528;
            sumW += W;
            sumWP += W * spc_glint_cell(dictionary, q, l, s, t);
        }
    }
    return sumW > 0.0 ? sumWP / sumW : 0.0;
}

// Explicit flakes (glint_flakes.h, same operations): the seed of Voronoi cell (x, y); the cell whose jittered point is
// nearest to uv (F1 Voronoi of uv / size over the 3 x 3 neighbourhood); the flake of a cell (present with probability
// relArea, slope m = L_f z with L_f the Cholesky factor of Sigma - sf^2 I, z by Box-Muller); and the footprint's flake
// density: the box uv + dx s + dy t read at 4 x 4 points (one for a zero footprint), sum of N(hs; m, sf^2 I) / points.
uint spc_glint_flake_seed(int x, int y) { return uint(x) * 73856093u + uint(y) * 19349663u + 83492791u; }
ivec2 spc_glint_flake_cell(vec2 uv, float size) {
    float px = uv.x / size, py = uv.y / size;
    float fx = floor(px), fy = floor(py);
    int ix = int(fx), iy = int(fy);
    float best = 1e30;
    ivec2 cell = ivec2(ix, iy);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            uint S = spc_glint_flake_seed(ix + dx, iy + dy);
            float ox = (fx + float(dx)) + spc_glint_hash(92821u * S) - px;
            float oy = (fy + float(dy)) + spc_glint_hash(68917u * S) - py;
            float d2 = ox * ox + oy * oy;
            if (d2 < best) {
                best = d2;
                cell = ivec2(ix + dx, iy + dy);
            }
        }
    }
    return cell;
}
bool spc_glint_flake_of_cell(ivec2 cell, float relArea, float sx, float sy, float r, float sf, out vec2 slope) {
    uint S = spc_glint_flake_seed(cell.x, cell.y);
    float rr = sqrt(-2.0 * log(spc_glint_hash(104729u * S)));
    float phi = 2.0 * SPC_PI * spc_glint_hash(1299709u * S);
    float z1 = rr * cos(phi), z2 = rr * sin(phi);
    float sf2 = sf * sf;
    float l00 = sqrt(sx * sx - sf2);
    float l10 = r * sx * sy / l00;
    float l11 = sqrt(max(sy * sy - sf2 - l10 * l10, 0.0));
    slope = vec2(l00 * z1, l10 * z1 + l11 * z2);
    return spc_glint_hash(7919u * S) <= relArea;
}
float spc_glint_flakes_sdf(vec2 uv, vec2 dx, vec2 dy, float size, float relArea, float sx, float sy, float r, float sf,
                           vec2 hs) {
    bool point = dx == vec2(0.0) && dy == vec2(0.0);
    int n = point ? 1 : 4;
    float sum = 0.0, v = sf * sf;
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            float ox = point ? 0.0 : -0.375 + 0.25 * float(i), oy = point ? 0.0 : -0.375 + 0.25 * float(j);
            vec2 p = vec2(uv.x + dx.x * ox + dy.x * oy, uv.y + dx.y * ox + dy.y * oy);
            vec2 m;
            if (spc_glint_flake_of_cell(spc_glint_flake_cell(p, size), relArea, sx, sy, r, sf, m)) {
                vec2 d = hs - m;
                sum += exp(-0.5 * (d.x * d.x + d.y * d.y) / v) / (2.0 * SPC_PI * v);
            }
        }
    }
    return sum / float(n * n);
}

vec3 spc_glint_frame_rotation(vec2 a, vec3 w) { return vec3(-a.x * w.z, -a.y * w.z, a.x * w.x + a.y * w.y); }

void spc_bsdf_glint(SpeculaClosureQuery q, SpeculaShadingInputs s, sampler1DArray dictionary, vec3 weight, float sigma_x, float sigma_y, float rho,
                    float log_density, float relative_area, float density_jitter, float max_anisotropy, int ggaa,
                    float kernel_scale, int derivative, int derivatives, int quad_lights, int fresnel, vec3 f0, float ior, vec3 eta, vec3 k,
                    vec3 base_color, vec2 lean_mean, vec3 lean_cov, vec3 normal,
                    vec3 tangent, vec2 uv, vec2 duvdx, vec2 duvdy, float uv_scale, vec3 dndx, vec3 dndy,
                    int footprint_centre, float flake_size, float flake_roughness, out SpeculaClosure bsdf) {
    // footprint_centre has no effect here: a fragment is at its pixel centre, so "sample" and "pixel" agree.
    bsdf = spc_closure_none();
    if (q.kind != SPC_QUERY_DIRECTION) {  // polygon queries: not in GLSL (the CPU has glint_area.h); the host samples this lobe
        bsdf.partial = true;
        return;
    }
    vec3 wo = q.wo, wi = q.wi;
    float sx = clamp(sigma_x, 0.01, 1.0), sy = clamp(sigma_y, 0.01, 1.0), r = clamp(rho, -0.99, 0.99);
    vec3 T, B, N;
    spc_frame(normal, tangent, T, B, N);
    // S6: LEAN combination and mean-slope frame.
    float vx = min(lean_cov.x, 1.0), vy = min(lean_cov.y, 1.0);
    if (vx > 1e-4 && vy > 1e-4) {
        float snx = sqrt(vx), sny = sqrt(vy);
        float rn = clamp(lean_cov.z / (snx * sny), -0.99, 0.99);
        float nsx = sqrt(sx * sx + vx), nsy = sqrt(sy * sy + vy);
        r = clamp((r * sx * sy + rn * snx * sny) / (nsx * nsy), -0.99, 0.99);
        sx = clamp(nsx, 0.01, 1.0);
        sy = clamp(nsy, 0.01, 1.0);
        vec3 m = normalize(N - lean_mean.x * T - lean_mean.y * B);
        float cw = dot(m, wo);
        if (cw < 0.0) m = normalize(m - 1.01 * cw * wo);
        vec3 Tn = T;
        spc_frame(m, Tn, T, B, N);
    }
    vec3 o = spc_to_local(wo, T, B, N);
    vec3 i = spc_to_local(wi, T, B, N);
    vec3 hsum = o + i;
    float len = sqrt(dot(hsum, hsum));
    vec3 h = len > 0.0 ? hsum / len : vec3(0.0, 0.0, 1.0);
    // Quad GGAA derivatives (C21 §6.1): the GGAA quantity of h differenced across the 2x2 quad, each h in its own
    // pixel's (normal-mapped, LEAN) frame with its own view and, for a point light, its own light direction, and this
    // query's light otherwise (a direction query fixes wi: the light's centre, the environment's normal). The quad
    // partner's frame, view and position come from dFdxFine/dFdyFine before any divergent return (they need the whole
    // quad); pixel x even (odd) has its partner at +1 (-1). The CPU twin differences against its quad partners
    // (GlintNeighbour, glint_ggaa.h) with the same rule.
    bool quadDerivatives = ggaa == SPC_GLINT_GGAA_ON && derivatives == SPC_GLINT_DERIVATIVES_QUAD;
    vec2 dqx = vec2(0.0), dqy = vec2(0.0);
    bool quadValid[2] = bool[2](false, false);
    if (quadDerivatives) {
        vec3 dT[2] = vec3[2](dFdxFine(T), dFdyFine(T)), dB[2] = vec3[2](dFdxFine(B), dFdyFine(B));
        vec3 dN[2] = vec3[2](dFdxFine(N), dFdyFine(N));
        // The view and the position move as the shading inputs say (specula_shading_inputs' dFdxFine, or a host's own).
        vec3 dWo[2] = vec3[2](s.dwodx, s.dwody), dP[2] = vec3[2](s.dPdx, s.dPdy);
        vec2 side = vec2((int(gl_FragCoord.x) & 1) == 0 ? 1.0 : -1.0, (int(gl_FragCoord.y) & 1) == 0 ? 1.0 : -1.0);
        bool pointLight = !isinf(q.light_distance) && q.light_distance > 0.0;
        vec2 qSelf = derivative == SPC_GLINT_DERIVATIVE_PROJECTED_HALF ? h.xy : -h.xy / max(h.z, 1e-30);
        for (int k = 0; k < 2; ++k) {
            float sg = side[k];
            vec3 woN = wo + sg * dWo[k];
            vec3 wiN = pointLight ? normalize(wi * q.light_distance - sg * dP[k]) : wi;
            vec3 hN = normalize(woN + wiN);
            vec3 hl = vec3(dot(hN, T + sg * dT[k]), dot(hN, B + sg * dB[k]), dot(hN, N + sg * dN[k]));
            if (hl.z > 0.0) {
                vec2 qN = derivative == SPC_GLINT_DERIVATIVE_PROJECTED_HALF ? hl.xy : -hl.xy / hl.z;
                quadValid[k] = true;
                if (k == 0) dqx = (qN - qSelf) * sg;
                else dqy = (qN - qSelf) * sg;
            }
        }
    }
    // S0 rejections.
    if (o.z <= 0.0 || i.z <= 0.0) return;
    if (!(len > 0.0)) return;
    float woh = dot(o, h), wih = dot(i, h);
    if (h.z <= 0.0 || woh <= 0.0 || wih <= 0.0) return;

    SpcGlintQuery gq;
    gq.sx = sx;
    gq.sy = sy;
    gq.rho = r;
    gq.sq = sqrt(1.0 - r * r);
    float mi00 = SPC_GLINT_SIGMA_O / (sx * gq.sq), mi01 = -SPC_GLINT_SIGMA_O * r / (sy * gq.sq), mi11 = SPC_GLINT_SIGMA_O / sy;
    gq.detMinv = SPC_GLINT_SIGMA_O * SPC_GLINT_SIGMA_O / (sx * sy * gq.sq);
    gq.relArea = relative_area;
    gq.jitter = density_jitter;
    // Flakes on: C20 counts one microfacet per flake area (glint_flakes.h flakeLogDensity).
    bool flakes = flake_size > 0.0 && !isinf(flake_size);
    gq.lcBase = (flakes ? -2.0 * log(flake_size) : log_density) / 1.38629436 - 15.0;
    vec2 hs = vec2(-h.x / h.z, -h.y / h.z);
    gq.mh = vec2(mi00 * hs.x + mi01 * hs.y, mi11 * hs.y);
    gq.pB = spc_glint_beckmann(hs, sx, sy, r, gq.sq);
    gq.ggaa = ggaa == SPC_GLINT_GGAA_ON;
    gq.gx = vec2(0.0);
    gq.gy = vec2(0.0);
    if (gq.ggaa) {
        vec2 dx = dqx, dy = dqy;
        if (!quadValid[0] || !quadValid[1]) {
            // The analytic form, per axis without a quad difference (derivatives "analytic", or a partner that sees
            // h below its horizon, as the CPU falls back): dh from the frame rotation (T.dN, B.dN) (C21 §6.1: once
            // per pixel, not per cell), plus the change of wo (s.dwodx) and, for a point light at q.light_distance,
            // of wi = -(I - wi wi^T) dp / dist.
            vec2 anx = vec2(dot(T, dndx), dot(B, dndx)), any = vec2(dot(T, dndy), dot(B, dndy));
            vec3 sx3 = spc_glint_frame_rotation(anx, o) + spc_to_local(s.dwodx, T, B, N) + spc_glint_frame_rotation(anx, i);
            vec3 sy3 = spc_glint_frame_rotation(any, o) + spc_to_local(s.dwody, T, B, N) + spc_glint_frame_rotation(any, i);
            if (!isinf(q.light_distance) && q.light_distance > 0.0) {
                vec3 dpx = spc_to_local(s.dPdx, T, B, N), dpy = spc_to_local(s.dPdy, T, B, N);
                sx3 -= (dpx - i * dot(i, dpx)) / q.light_distance;
                sy3 -= (dpy - i * dot(i, dpy)) / q.light_distance;
            }
            vec3 dhx = (sx3 - h * dot(h, sx3)) / len, dhy = (sy3 - h * dot(h, sy3)) / len;
            vec2 ax, ay;
            if (derivative == SPC_GLINT_DERIVATIVE_PROJECTED_HALF) {  // projected half vector (C21 Eq. 21)
                ax = dhx.xy;
                ay = dhy.xy;
            } else {  // half slope (C21 Eq. 20)
                float iz2 = 1.0 / (h.z * h.z);
                ax = vec2(-(dhx.x * h.z - h.x * dhx.z) * iz2, -(dhx.y * h.z - h.y * dhx.z) * iz2);
                ay = vec2(-(dhy.x * h.z - h.x * dhy.z) * iz2, -(dhy.y * h.z - h.y * dhy.z) * iz2);
            }
            if (!quadValid[0]) dx = ax;
            if (!quadValid[1]) dy = ay;
        }
        float kk = kernel_scale / SPC_GLINT_LIM;
        gq.gx = vec2(mi00 * dx.x + mi01 * dx.y, mi11 * dx.y) * kk;
        gq.gy = vec2(mi00 * dy.x + mi01 * dy.y, mi11 * dy.y) * kk;
    }

    // S1/S2: footprint and LOD.
    vec2 J1 = duvdx * uv_scale, J2 = duvdy * uv_scale, suv = uv * uv_scale;
    float l1 = dot(J1, J1), l2 = dot(J2, J2);
    vec2 a1 = l1 >= l2 ? J1 : J2, a2 = l1 >= l2 ? J2 : J1;
    float la1 = sqrt(max(l1, l2)), la2 = sqrt(min(l1, l2));
    float amax = max(max_anisotropy, 1.0);
    bool footprintValid = la2 > 0.0 && !isinf(la1) && !isnan(la1);
    if (footprintValid && la1 > amax * la2) {
        a2 = a2 * (la1 / (amax * la2));
        la2 = la1 / amax;
    }
    // Explicit flakes (glint_flakes.h): weight 1 - smoothstep(1/2, 1, footprint / flake size) on the flakes of the
    // fragment's footprint (a fragment is its pixel's centre), the rest on C20's counting.
    float we = 0.0, pFlake = 0.0;
    vec2 fuv = uv * uv_scale;
    if (flakes && abs(fuv.x / flake_size) < 8388608.0 && abs(fuv.y / flake_size) < 8388608.0) {
        float width = footprintValid ? sqrt(sqrt(dot(a1, a1) * dot(a2, a2))) : 0.0;
        float x = clamp((width / flake_size - 0.5) / 0.5, 0.0, 1.0);
        we = width > 0.0 ? 1.0 - x * x * (3.0 - 2.0 * x) : 1.0;
    }
    // Only where the flakes show (as the CPU lobe, which finds them only then): 16 Voronoi searches per fragment.
    if (we > 0.0) {
        float ea = sx * sx, ec = sy * sy, eb = r * sx * sy;
        float minEigen = 0.5 * (ea + ec - sqrt((ea - ec) * (ea - ec) + 4.0 * eb * eb));
        float sf = max(min(flake_roughness >= 1e-3 ? flake_roughness : 1e-3, sqrt(0.8 * max(minEigen, 0.0))), 1e-4);
        vec2 fx = footprintValid ? J1 : vec2(0.0), fy = footprintValid ? J2 : vec2(0.0);
        pFlake = spc_glint_flakes_sdf(fuv, fx, fy, flake_size, relative_area, sx, sy, r, sf, hs);
    }
    float P = 0.0;
    if (we < 1.0) {
        if (!footprintValid) {
            P = gq.pB;
        } else {
            float lodP = clamp(15.0 + log2(la2), 0.0, 15.0);
            float i0f = floor(lodP);
            int i0 = int(i0f);
            float w = lodP - i0f;
            P = spc_glint_level(dictionary, gq, i0, suv, a1, a2);
            if (w > 0.0) P = (1.0 - w) * P + w * spc_glint_level(dictionary, gq, min(i0 + 1, 15), suv, a1, a2);
        }
    }
    P = (1.0 - we) * P + we * pFlake;
    // S7: D = P / h_z^4, V-cavity G, F at wo.h (glint-brdf.md §1; the fresnelPorts model, as GlintLobe's Fresnel);
    // returns f cos = base_color F G D / (4 wo.z).
    float hz2 = h.z * h.z;
    float D = P / (hz2 * hz2);
    float G = min(1.0, 2.0 * h.z * o.z / woh) * min(1.0, 2.0 * h.z * i.z / wih);
    float fc = G * D / (4.0 * o.z);
    if (!(fc > 0.0)) return;
    vec3 F = spc_fresnel_eval(fresnel, woh, f0, ior, eta, k);  // shared/fresnel_f0.glsl
    bsdf.f = (weight * base_color) * (F * fc);
}
