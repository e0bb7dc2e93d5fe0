/* Looks up a texture whose name is made while the shader runs: only the
 * lookup itself can tell that it is one of the job's outputs. */
surface runtime_lookup(string prefix = "tex") {
    string name = concat(prefix, ".exr");
    Ci = color texture(name);
    Oi = Os;
}
