displacement dent(float Km = 0.1; float freq = 4)
{
    float amp = Km * float noise(P * freq);
    P += amp * normalize(N);
    N = calculatenormal(P);
}
