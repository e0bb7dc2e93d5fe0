/* ambientlight: light arriving from no direction (RISpec 3.2, appendix A). */
light ambientlight(float intensity = 1; color lightcolor = 1;)
{
    Cl = intensity * lightcolor;
}
