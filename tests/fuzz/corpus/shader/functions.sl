float twice(float x) { return 2 * x; }
void acc(output color a; color c) { a += c; }
surface funcs(float Kd = 1; string map = "t.tx"; float w[3] = {1, 2, 3};
              output varying color aov = 0)
{
    color total = 0;
    float scale(float y) { extern float Kd; return y * Kd; }
    float i, a[4] = {0, 1, 2, 3};
    for (i = 0; i < 4; i += 1) {
        if (a[i] > u) break;
        else continue;
        acc(total, color texture(map[1], s, t, "blur", 0.01));
    }
    while (i > 0) { i -= 1; if (v > 0.5) break 1; }
    illuminance("-diffuse", P, N, PI / 2) { total += Cl * (normalize(L) . N); }
    color h = color "hsv" (0.5, 1, 1);
    matrix m = matrix "world" (1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1);
    point q = transform("object", P) + vector noise(P * 4);
    aov = total;
    Ci = total * twice(scale(w[1])) * h * (u > 0.5 ? 1 : 0.5) + comp(m, 0, 0);
}
