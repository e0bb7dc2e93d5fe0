/* Compiles; with broken.sl on the same command line nothing is written. */
surface good() { Ci = 1; Oi = Os; }
