// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* Jensen et al. 2001's measured materials as the albedo and diffuse mean
 * free path (mm) the classic dipole gives them: the presets of ptfilter's
 * -material, for bake shaders. Generated from the diffusion library's
 * material table (docs/shading.md). Unknown names leave the outputs alone
 * and return 0. */
#ifndef SSS_MATERIALS_H
#define SSS_MATERIALS_H

float sss_material(string name; output color albedo, dmfp)
{
    float known = 1;
    if (name == "apple") {
        albedo = color(0.846416241, 0.840675185, 0.52785481);
        dmfp = color(6.96108149, 6.40018121, 1.89589898);
    } else if (name == "chicken1") {
        albedo = color(0.31367921, 0.155805431, 0.126444469);
        dmfp = color(11.6051771, 3.88376606, 1.75438596);
    } else if (name == "chicken2") {
        albedo = color(0.321238824, 0.159938454, 0.107631535);
        dmfp = color(9.43564195, 3.34764723, 1.79028719);
    } else if (name == "cream") {
        albedo = color(0.975736709, 0.900015959, 0.724731628);
        dmfp = color(15.0276236, 4.66396807, 2.5413796);
    } else if (name == "ketchup") {
        albedo = color(0.163836011, 0.00633693108, 0.00182980502);
        dmfp = color(4.7617428, 0.574826572, 0.394116406);
    } else if (name == "marble") {
        albedo = color(0.830191456, 0.790960197, 0.752609945);
        dmfp = color(8.50941186, 5.56618009, 3.95126596);
    } else if (name == "potato") {
        albedo = color(0.764421914, 0.612500474, 0.212706547);
        dmfp = color(14.2663949, 7.22761483, 2.03615741);
    } else if (name == "skimmilk") {
        albedo = color(0.814945956, 0.812984199, 0.682295165);
        dmfp = color(18.4243627, 10.4434727, 3.50188229);
    } else if (name == "skin1") {
        albedo = color(0.43595636, 0.227331199, 0.130998825);
        dmfp = color(3.67329437, 1.36653344, 0.682693267);
    } else if (name == "skin2") {
        albedo = color(0.622630862, 0.433271238, 0.343457643);
        dmfp = color(4.82147523, 1.6936993, 1.08997086);
    } else if (name == "wholemilk") {
        albedo = color(0.907698457, 0.880868497, 0.759412709);
        dmfp = color(10.8988152, 6.57535103, 2.50841732);
    } else {
        known = 0;
    }
    return known;
}
#endif
