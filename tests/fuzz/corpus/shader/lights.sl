light spotlight(float intensity = 1; color lightcolor = 1;
                point from = point "shader" (0, 0, 0); point to = point "shader" (0, 0, 1);
                float coneangle = radians(30); float conedeltaangle = radians(5);
                float beamdistribution = 2; string shadowname = "")
{
    uniform vector A = normalize(to - from);
    uniform float cosoutside = cos(coneangle), cosinside = cos(coneangle - conedeltaangle);
    illuminate(from, A, coneangle) {
        float cosangle = L . A / length(L);
        float atten = pow(cosangle, beamdistribution) / (L . L);
        atten *= smoothstep(cosoutside, cosinside, cosangle);
        if (shadowname != "") atten *= 1 - shadow(shadowname[0], Ps, "samples", 16);
        Cl = atten * intensity * lightcolor;
    }
}
light distant(vector dir = vector (0, 0, 1)) { solar(dir, 0) { Cl = 1; } }
