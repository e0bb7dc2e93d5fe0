// RSL 2.0: a class with member variables, pipeline methods, a private
// method and co-shader calls.
class layered(float Kd = 0.8; string base = "base"; output varying color extra = 0;) {
    varying color m_pattern;
    uniform shader m_base;
    constant float m_levels = 3;
    float boost(float x) { return x * Kd; }
    public void begin() { m_base = getshader(base); }
    public void opacity(output color Oi) { Oi = Os; }
    public void prelighting(output color Ci, Oi) {
        m_pattern = Cs;
        if (m_base != null && hasmethod(m_base, "value")) m_pattern *= m_base->value(s);
    }
    public void lighting(output color Ci, Oi) {
        normal Nf = faceforward(normalize(N), I);
        shader lights[] = getlights("category", "-fill");
        uniform float i, n = arraylength(lights);
        color sum = 0;
        for (i = 0; i < n; i += 1) {
            vector L;
            color Cl;
            lights[i]->light(L, Cl);
            sum += Cl * max(0, normalize(-L) . Nf);
        }
        float k = 1;
        getvar(m_base, "gain", k);
        Ci = m_pattern * boost(k) * sum;
    }
    public void postlighting(output color Ci, Oi) { Ci *= Oi; extra = m_pattern; }
    public color pattern() { return m_pattern; }
}
