// closure.add: a + b.
void spc_closure_add(SpeculaClosure a, SpeculaClosure b, out SpeculaClosure bsdf) {
    bsdf.f = a.f + b.f;
    bsdf.f_diffuse = a.f_diffuse + b.f_diffuse;
    bsdf.emission = a.emission + b.emission;
    bsdf.partial = a.partial || b.partial;
}
