// closure.mix: a * (1 - t) + b * t.
void spc_closure_mix(SpeculaClosure a, SpeculaClosure b, float t, out SpeculaClosure o) {
    o.f = a.f * (1.0 - t) + b.f * t;
    o.emission = a.emission * (1.0 - t) + b.emission * t;
}
