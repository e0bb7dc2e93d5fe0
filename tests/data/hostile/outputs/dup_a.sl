/* Defines shader "dup", as dup_b.sl does: both would write dup.slo. */
surface dup() { Ci = 1; Oi = Os; }
