// bsdf.sheen: f·cos = color · D(h) G2(wo, wi) / (4 cos θo), the GLSL twin of SheenLobe::evalPdf (sheen_lobe.h, which
// cites Estevez & Kulla 2017 for each formula): D the Charlie distribution, G2 = 1/(1 + Λo + Λi) with their fitted Λ.
// Polygon and environment queries: no closed form, so the closure is partial and the host samples this lobe.
float spc_sheen_lambda_exponent(float x, float alpha) {
    float t = (1.0 - alpha) * (1.0 - alpha);
    float a = mix(21.5473, 25.3245, t), b = mix(3.82987, 3.32435, t), c = mix(0.19823, 0.16801, t);
    float d = mix(-1.97760, -1.27393, t), e = mix(-4.32054, -4.85967, t);
    return a / (1.0 + b * pow(x, c)) + d * x + e;
}
float spc_sheen_lambda(float cosTheta, float alpha) {
    if (cosTheta < 0.5) return exp(spc_sheen_lambda_exponent(cosTheta, alpha));
    // 1 - cos is clamped at 0: a unit vector's z can round above 1, and pow of a negative base is undefined.
    float x = max(1.0 - cosTheta, 0.0);
    return exp(2.0 * spc_sheen_lambda_exponent(0.5, alpha) - spc_sheen_lambda_exponent(x, alpha));
}
void spc_bsdf_sheen(SpeculaClosureQuery q, vec3 color, float roughness, vec3 normal, out SpeculaClosure bsdf) {
    bsdf = spc_closure_none();
    if (q.kind != SPC_QUERY_DIRECTION) {
        bsdf.partial = true;
        return;
    }
    float alpha = clamp(roughness, 0.08, 1.0);  // sheen::kMinAlpha
    vec3 o, i, h;
    if (!spc_reflection_local(q.wo, q.wi, normal, vec3(1.0, 0.0, 0.0), o, i, h)) return;
    float invAlpha = 1.0 / alpha;
    float D = (2.0 + invAlpha) * pow(max(1.0 - h.z * h.z, 0.0), 0.5 * invAlpha) * (0.5 * SPC_INV_PI);
    float G = 1.0 / (1.0 + spc_sheen_lambda(o.z, alpha) + spc_sheen_lambda(i.z, alpha));
    bsdf.f = color * (D * G / (4.0 * o.z));
    bsdf.f_diffuse = bsdf.f;  // SheenLobe is of the diffuse category
}
