// closure.mix: a * (1 - t) + b * t.
void spc_closure_mix(SpeculaClosure a, SpeculaClosure b, float t, out SpeculaClosure bsdf) {
    bsdf.f = a.f * (1.0 - t) + b.f * t;
    bsdf.f_diffuse = a.f_diffuse * (1.0 - t) + b.f_diffuse * t;
    bsdf.emission = a.emission * (1.0 - t) + b.emission * t;
    bsdf.partial = a.partial || b.partial;
}
