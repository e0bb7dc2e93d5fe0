/// \file rsl_noise.cpp
/// RSL's noise(), pnoise() and cellnoise() in 1 to 4 dimensions (rsl_math.h).
///
/// noise is Ken Perlin's improved gradient noise (SIGGRAPH 2002) scaled to
/// 0.5*(1+n). The 3-D form is the same construction as sss::noise3 (module
/// light, used by the baker): the same seeded permutation, the same 16
/// gradients, the same arithmetic in double, so that it returns exactly the
/// same values and existing bakes keep their patterns. The module layering
/// forbids calling it from here, hence the copy; a test compares both.
/// The other dimensions extend the construction: 1-D gradients are slopes
/// in [-2, 2], 2-D ones the 8 directions to a square's edges and corners,
/// 4-D ones the 32 directions to a hypercube's edge midpoints.

#include <array>
#include <cmath>
#include <cstdint>
#include <initializer_list>

#include "rsl_math.h"
#include "sss/light/lights.h"
#include "sss/util/hash.h"

namespace sss::detail {

namespace {

/// The permutation, stored twice so that p[p[x] + y] needs no wrapping.
using PermutationTable = std::array<uint8_t, 512>;

/// light's noise3 permutation: RSL's 3-D noise equals noise3.
const PermutationTable& permutation() {
    return noise_permutation();
}

/// 3-D gradients: the 12 cube-edge directions, 4 repeated to make 16 (Perlin
/// 2002); identical to light/noise.cpp.
constexpr int kGradients3[16][3] = {{1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0},
                                    {1, 0, 1}, {-1, 0, 1}, {1, 0, -1}, {-1, 0, -1},
                                    {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1},
                                    {1, 1, 0}, {0, -1, 1}, {-1, 1, 0}, {0, -1, -1}};

constexpr int kGradients2[8][2] = {{1, 1}, {-1, 1}, {1, -1}, {-1, -1},
                                   {1, 0}, {-1, 0}, {0, 1},  {0, -1}};

/// 4-D: the 32 vectors with one zero and three +-1 components.
constexpr std::array<std::array<int, 4>, 32> make_gradients4() {
    std::array<std::array<int, 4>, 32> g{};
    int n = 0;
    for (int zero = 0; zero < 4; ++zero)
        for (int signs = 0; signs < 8; ++signs) {
            int bit = 0;
            for (int d = 0; d < 4; ++d)
                g[n][d] = d == zero ? 0 : ((signs >> bit++) & 1 ? -1 : 1);
            ++n;
        }
    return g;
}
constexpr auto kGradients4 = make_gradients4();

template <int D>
double grad_dot(int hash, const double* x) {
    if constexpr (D == 1) {
        // Slopes +-0.25 .. +-2 so that the 1-D noise reaches +-1 at most.
        const double g = 0.25 * ((hash & 7) + 1);
        return (hash & 8 ? -g : g) * x[0];
    } else if constexpr (D == 2) {
        const int* g = kGradients2[hash & 7];
        return g[0] * x[0] + g[1] * x[1];
    } else if constexpr (D == 3) {
        const int* g = kGradients3[hash & 15];
        return g[0] * x[0] + g[1] * x[1] + g[2] * x[2];
    } else {
        const auto& g = kGradients4[hash & 31];
        return g[0] * x[0] + g[1] * x[1] + g[2] * x[2] + g[3] * x[3];
    }
}

/// 6t^5 - 15t^4 + 10t^3: zero first and second derivatives at 0 and 1.
double fade(double t) {
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

double lerp(double t, double a, double b) {
    return a + t * (b - a);
}

/// The lattice cells either side of x along one axis, as permutation indices
/// in [0, 255], and the offset of x inside its cell. `period` < 1: the
/// lattice repeats every 256 cells (the permutation's own period), as in
/// light/noise.cpp; otherwise every `period` cells. `shift` decorrelates the
/// components of vector noise (an integer lattice shift keeps the value 0.5
/// on lattice points and keeps the period).
struct Axis {
    int i0 = 0, i1 = 0;
    double frac = 0.0;
};

Axis axis(double x, double period, int shift) {
    Axis a;
    const double f = std::floor(x);
    a.frac = x - f;
    // Reducing in double keeps huge coordinates from overflowing an int.
    // 256 divides exactly (the formula of light/noise.cpp); other periods
    // use fmod, which is exact where f - n*floor(f/n) may round out of
    // [0, n) for huge f.
    const double n = period >= 1.0 ? period : 256.0;
    double wrapped;
    if (n == 256.0) {
        wrapped = f - n * std::floor(f / n);
    } else {
        wrapped = std::fmod(f, n);
        if (wrapped < 0.0) wrapped += n;
    }
    const auto c0 = static_cast<int64_t>(wrapped);
    const auto p = static_cast<int64_t>(n);
    const int64_t c1 = c0 + 1 == p ? 0 : c0 + 1;
    a.i0 = static_cast<int>((c0 + shift) & 255);
    a.i1 = static_cast<int>((c1 + shift) & 255);
    return a;
}

/// Signed gradient noise, roughly in [-1, 1], 0 on every lattice point.
/// periods[d] < 1: not periodic along d.
template <int D>
double gradient_noise(const double* x, const double* periods, int component) {
    // Per-component lattice shifts (arbitrary, distinct mod 256).
    static constexpr int kShift[3][4] = {
        {0, 0, 0, 0}, {97, 13, 181, 59}, {211, 149, 37, 113}};
    const PermutationTable& p = permutation();
    Axis ax[D];
    double u[D];
    for (int d = 0; d < D; ++d) {
        ax[d] = axis(x[d], periods ? periods[d] : 0.0, kShift[component][d]);
        u[d] = fade(ax[d].frac);
    }
    constexpr int kCorners = 1 << D;
    double v[kCorners];
    for (int c = 0; c < kCorners; ++c) {
        int h = 0;
        double offset[D];
        for (int d = 0; d < D; ++d) {
            const bool upper = (c >> d) & 1;
            h = p[h + (upper ? ax[d].i1 : ax[d].i0)];
            offset[d] = upper ? ax[d].frac - 1.0 : ax[d].frac;
        }
        v[c] = grad_dot<D>(h, offset);
    }
    // Interpolate x first, then y, z, w: the order of light/noise.cpp.
    for (int d = 0, n = kCorners; d < D; ++d, n /= 2)
        for (int c = 0; c < n / 2; ++c) v[c] = lerp(u[d], v[2 * c], v[2 * c + 1]);
    return v[0];
}

/// 0.5*(1+n) clamped to [0,1] (improved noise can slightly exceed [-1,1]).
/// A non-finite coordinate gives 0.5: a shader's NaN must not stop the
/// render, and the lattice arithmetic is undefined on it.
template <int D>
float noise01(const double* x, const double* periods, int component) {
    for (int d = 0; d < D; ++d)
        if (!std::isfinite(x[d])) return 0.5f;
    // 4-D gradient noise spreads wider (about 1.1x the 3-D one's standard
    // deviation, and past +-1 now and then): 0.9 matches the 3-D spread.
    constexpr double kScale = D == 4 ? 0.9 : 1.0;
    const double n = 0.5 + 0.5 * kScale * gradient_noise<D>(x, periods, component);
    return static_cast<float>(n < 0.0 ? 0.0 : (n > 1.0 ? 1.0 : n));
}

template <int D>
glm::vec3 vnoise01(const double* x, const double* periods) {
    return {noise01<D>(x, periods, 0), noise01<D>(x, periods, 1),
            noise01<D>(x, periods, 2)};
}

/// pnoise periods: rounded to integers; < 1 means not periodic.
/// Periods of 2^30 and more (beyond float's integers anyway) are treated as
/// not periodic, which keeps the cell arithmetic in range.
double period_of(float p) {
    const double r = std::isfinite(p) ? std::round(static_cast<double>(p)) : 0.0;
    return r < 0x1.0p30 ? r : 0.0;
}

/// The integer cell of x; non-finite coordinates fall in cell 0, huge ones
/// saturate.
int64_t cell_index(float x) {
    if (!std::isfinite(x)) return 0;
    const double f = std::floor(static_cast<double>(x));
    if (f >= 9.0e18) return INT64_MAX;
    if (f <= -9.0e18) return INT64_MIN;
    return static_cast<int64_t>(f);
}

/// A uniform float in [0, 1) hashed from the cells and a component seed.
float cell_hash(std::initializer_list<float> coords, uint64_t component) {
    uint64_t h = splitmix64(0x63656c6c'6e6f6973ull + component); // "cellnois"
    for (float x : coords) h = splitmix64(h ^ static_cast<uint64_t>(cell_index(x)));
    // The top 24 bits: exactly representable, so the float stays below 1.
    return static_cast<float>(h >> 40) * 0x1.0p-24f;
}

glm::vec3 vcell_hash(std::initializer_list<float> coords) {
    return {cell_hash(coords, 0), cell_hash(coords, 1), cell_hash(coords, 2)};
}

} // namespace

float rsl_noise(float x) {
    const double c[1] = {x};
    return noise01<1>(c, nullptr, 0);
}
float rsl_noise(float x, float y) {
    const double c[2] = {x, y};
    return noise01<2>(c, nullptr, 0);
}
float rsl_noise(const glm::vec3& p) {
    const double c[3] = {p.x, p.y, p.z};
    return noise01<3>(c, nullptr, 0);
}
float rsl_noise(const glm::vec3& p, float t) {
    const double c[4] = {p.x, p.y, p.z, t};
    return noise01<4>(c, nullptr, 0);
}

glm::vec3 rsl_vnoise(float x) {
    const double c[1] = {x};
    return vnoise01<1>(c, nullptr);
}
glm::vec3 rsl_vnoise(float x, float y) {
    const double c[2] = {x, y};
    return vnoise01<2>(c, nullptr);
}
glm::vec3 rsl_vnoise(const glm::vec3& p) {
    const double c[3] = {p.x, p.y, p.z};
    return vnoise01<3>(c, nullptr);
}
glm::vec3 rsl_vnoise(const glm::vec3& p, float t) {
    const double c[4] = {p.x, p.y, p.z, t};
    return vnoise01<4>(c, nullptr);
}

float rsl_pnoise(float x, float px) {
    const double c[1] = {x}, per[1] = {period_of(px)};
    return noise01<1>(c, per, 0);
}
float rsl_pnoise(float x, float y, float px, float py) {
    const double c[2] = {x, y}, per[2] = {period_of(px), period_of(py)};
    return noise01<2>(c, per, 0);
}
float rsl_pnoise(const glm::vec3& p, const glm::vec3& period) {
    const double c[3] = {p.x, p.y, p.z};
    const double per[3] = {period_of(period.x), period_of(period.y), period_of(period.z)};
    return noise01<3>(c, per, 0);
}
float rsl_pnoise(const glm::vec3& p, float t, const glm::vec3& period, float pt) {
    const double c[4] = {p.x, p.y, p.z, t};
    const double per[4] = {period_of(period.x), period_of(period.y), period_of(period.z),
                           period_of(pt)};
    return noise01<4>(c, per, 0);
}

glm::vec3 rsl_vpnoise(float x, float px) {
    const double c[1] = {x}, per[1] = {period_of(px)};
    return vnoise01<1>(c, per);
}
glm::vec3 rsl_vpnoise(float x, float y, float px, float py) {
    const double c[2] = {x, y}, per[2] = {period_of(px), period_of(py)};
    return vnoise01<2>(c, per);
}
glm::vec3 rsl_vpnoise(const glm::vec3& p, const glm::vec3& period) {
    const double c[3] = {p.x, p.y, p.z};
    const double per[3] = {period_of(period.x), period_of(period.y), period_of(period.z)};
    return vnoise01<3>(c, per);
}
glm::vec3 rsl_vpnoise(const glm::vec3& p, float t, const glm::vec3& period, float pt) {
    const double c[4] = {p.x, p.y, p.z, t};
    const double per[4] = {period_of(period.x), period_of(period.y), period_of(period.z),
                           period_of(pt)};
    return vnoise01<4>(c, per);
}

// Each dimension count hashes its own number of coordinates, so
// cellnoise(x) and cellnoise(x, 0) are independent.
float rsl_cellnoise(float x) {
    return cell_hash({x}, 0);
}
float rsl_cellnoise(float x, float y) {
    return cell_hash({x, y}, 0);
}
float rsl_cellnoise(const glm::vec3& p) {
    return cell_hash({p.x, p.y, p.z}, 0);
}
float rsl_cellnoise(const glm::vec3& p, float t) {
    return cell_hash({p.x, p.y, p.z, t}, 0);
}
glm::vec3 rsl_vcellnoise(float x) {
    return vcell_hash({x});
}
glm::vec3 rsl_vcellnoise(float x, float y) {
    return vcell_hash({x, y});
}
glm::vec3 rsl_vcellnoise(const glm::vec3& p) {
    return vcell_hash({p.x, p.y, p.z});
}
glm::vec3 rsl_vcellnoise(const glm::vec3& p, float t) {
    return vcell_hash({p.x, p.y, p.z, t});
}

} // namespace sss::detail
