/* Reads a texture's header (textureinfo) by a name made while the shader
 * runs. */
surface runtime_info(string prefix = "tex") {
    string name = concat(prefix, ".exr");
    float res[2] = {0, 0};
    float ok = textureinfo(name, "resolution", res);
    Ci = color(ok, res[0], res[1]);
    Oi = Os;
}
