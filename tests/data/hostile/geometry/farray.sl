/* Traces rays that start beyond the ray tracer's range, and rays that start
   nowhere (NaN): they must be counted misses, never reach Embree. */
surface farray()
{
    point far = P + vector(1e30, 0, 0);
    point nowhere = P * sqrt(-1);
    Ci = trace(far, N) + trace(nowhere, N) + color(0.5);
    Oi = 1;
}
