/* Does not compile: an undeclared variable. */
surface broken() { Ci = nosuchvariable; Oi = Os; }
