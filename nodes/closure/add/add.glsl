// closure.add: a + b.
void spc_closure_add(SpeculaClosure a, SpeculaClosure b, out SpeculaClosure o) {
    o.f = a.f + b.f;
    o.emission = a.emission + b.emission;
}
