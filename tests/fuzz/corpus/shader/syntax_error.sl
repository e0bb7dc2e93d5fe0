surface bad() {
    float x = 1
    Ci = x;
    color c = P;
}
