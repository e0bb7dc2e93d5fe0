/* Defines shader "dup", as dup_a.sl does: both would write dup.slo. */
surface dup() { Ci = 0.5; Oi = Os; }
