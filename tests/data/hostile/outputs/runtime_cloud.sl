/* A bake shader that also looks a point cloud up (texture3d) by a name made
 * while it runs. */
surface runtime_cloud(string filename = ""; string prefix = "keep") {
    string name = concat(prefix, ".ptc");
    color c = 0;
    texture3d(name, P, N, "_radiance_t", c);
    bake3d(filename, "", P, normalize(N), "interpolate", 1, "_radiance_t", c);
    Ci = c;
    Oi = Os;
}
