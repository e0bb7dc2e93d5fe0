surface bad() {
    Ci = foo;
    Oi = bar;
    Ci = 1 + "a";
}
