/* constant: the surface colour, unlit (RISpec 3.2, appendix A). */
surface constant()
{
    Oi = Os;
    Ci = Os * Cs;
}
