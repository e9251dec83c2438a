// MGF's colours as RGB (mgf.h): chromaticities from spectra (cspec), black
// bodies (cct) and mixtures (cmix), and the conversion of a chromaticity
// and a luminance to RGB in Radiance's standard primaries, as mgf2rad
// converts them.

#include "io/readers/mgf.h"

#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <array>
#include <cmath>

namespace radmesh::internal::mgf {

namespace {

// The CIE 1931 2-degree colour matching functions x, y, z from 380 to 780
// nm every 5 nm (the CIE's table to 4 decimals).
constexpr int kCmfFirst = 380, kCmfStep = 5, kCmfCount = 81;
constexpr double kCmf[kCmfCount][3] = {
    {0.0014, 0.0000, 0.0065}, {0.0022, 0.0001, 0.0105}, {0.0042, 0.0001, 0.0201}, {0.0076, 0.0002, 0.0362},
    {0.0143, 0.0004, 0.0679}, {0.0232, 0.0006, 0.1102}, {0.0435, 0.0012, 0.2074}, {0.0776, 0.0022, 0.3713},
    {0.1344, 0.0040, 0.6456}, {0.2148, 0.0073, 1.0391}, {0.2839, 0.0116, 1.3856}, {0.3285, 0.0168, 1.6230},
    {0.3483, 0.0230, 1.7471}, {0.3481, 0.0298, 1.7826}, {0.3362, 0.0380, 1.7721}, {0.3187, 0.0480, 1.7441},
    {0.2908, 0.0600, 1.6692}, {0.2511, 0.0739, 1.5281}, {0.1954, 0.0910, 1.2876}, {0.1421, 0.1126, 1.0419},
    {0.0956, 0.1390, 0.8130}, {0.0580, 0.1693, 0.6162}, {0.0320, 0.2080, 0.4652}, {0.0147, 0.2586, 0.3533},
    {0.0049, 0.3230, 0.2720}, {0.0024, 0.4073, 0.2123}, {0.0093, 0.5030, 0.1582}, {0.0291, 0.6082, 0.1117},
    {0.0633, 0.7100, 0.0782}, {0.1096, 0.7932, 0.0573}, {0.1655, 0.8620, 0.0422}, {0.2257, 0.9149, 0.0298},
    {0.2904, 0.9540, 0.0203}, {0.3597, 0.9803, 0.0134}, {0.4334, 0.9950, 0.0087}, {0.5121, 1.0000, 0.0057},
    {0.5945, 0.9950, 0.0039}, {0.6784, 0.9786, 0.0027}, {0.7621, 0.9520, 0.0021}, {0.8425, 0.9154, 0.0018},
    {0.9163, 0.8700, 0.0017}, {0.9786, 0.8163, 0.0014}, {1.0263, 0.7570, 0.0011}, {1.0567, 0.6949, 0.0010},
    {1.0622, 0.6310, 0.0008}, {1.0456, 0.5668, 0.0006}, {1.0026, 0.5030, 0.0003}, {0.9384, 0.4412, 0.0002},
    {0.8544, 0.3810, 0.0002}, {0.7514, 0.3210, 0.0001}, {0.6424, 0.2650, 0.0000}, {0.5419, 0.2170, 0.0000},
    {0.4479, 0.1750, 0.0000}, {0.3608, 0.1382, 0.0000}, {0.2835, 0.1070, 0.0000}, {0.2187, 0.0816, 0.0000},
    {0.1649, 0.0610, 0.0000}, {0.1212, 0.0446, 0.0000}, {0.0874, 0.0320, 0.0000}, {0.0636, 0.0232, 0.0000},
    {0.0468, 0.0170, 0.0000}, {0.0329, 0.0119, 0.0000}, {0.0227, 0.0082, 0.0000}, {0.0158, 0.0057, 0.0000},
    {0.0114, 0.0041, 0.0000}, {0.0081, 0.0029, 0.0000}, {0.0058, 0.0021, 0.0000}, {0.0041, 0.0015, 0.0000},
    {0.0029, 0.0010, 0.0000}, {0.0020, 0.0007, 0.0000}, {0.0014, 0.0005, 0.0000}, {0.0010, 0.0004, 0.0000},
    {0.0007, 0.0002, 0.0000}, {0.0005, 0.0002, 0.0000}, {0.0003, 0.0001, 0.0000}, {0.0002, 0.0001, 0.0000},
    {0.0002, 0.0001, 0.0000}, {0.0001, 0.0000, 0.0000}, {0.0001, 0.0000, 0.0000}, {0.0001, 0.0000, 0.0000},
    {0.0000, 0.0000, 0.0000}};

// Spectra are integrated every nanometre, the matching functions linear
// between the table's rows.
constexpr int kSamples = (kCmfCount - 1) * kCmfStep + 1;

struct Cmf {
  std::array<Vec3, kSamples> at;  // (x, y, z) at 380 + i nm
  Vec3 sum{0.0};                  // over all samples
};

const Cmf& cmf() {
  static const Cmf table = [] {
    Cmf t;
    for (int i = 0; i < kSamples; ++i) {
      const int row = std::min(i / kCmfStep, kCmfCount - 2);
      const double f = static_cast<double>(i - row * kCmfStep) / kCmfStep;
      const Vec3 a(kCmf[row][0], kCmf[row][1], kCmf[row][2]);
      const Vec3 b(kCmf[row + 1][0], kCmf[row + 1][1], kCmf[row + 1][2]);
      t.at[static_cast<size_t>(i)] = a + f * (b - a);
      t.sum += t.at[static_cast<size_t>(i)];
    }
    return t;
  }();
  return table;
}

// XYZ of a spectrum given per sample, each matching function divided by its
// sum: the equal-energy spectrum has X = Y = Z, the white of MGF and of
// Radiance's primaries.
Vec3 xyz_of(const std::array<double, kSamples>& spectrum) {
  const Cmf& t = cmf();
  Vec3 xyz(0.0);
  for (size_t i = 0; i < kSamples; ++i) xyz += spectrum[i] * t.at[i];
  return xyz / t.sum;
}

std::string chromaticity_of(const Vec3& xyz, Chromaticity* out) {
  const double total = xyz.x + xyz.y + xyz.z;
  if (!(xyz.y > 0.0) || !(total > 0.0) || !std::isfinite(total)) return "has no luminance in the visible range (380 to 780 nm)";
  out->x = xyz.x / total;
  out->y = xyz.y / total;
  return "";
}

// XYZ -> RGB in Radiance's standard primaries, each scaled so that
// (1, 1, 1) is the equal-energy white of luminance 1.
const glm::dmat3& xyz_to_rgb() {
  static const glm::dmat3 m = [] {
    const double xy[3][2] = {{0.640, 0.330}, {0.290, 0.600}, {0.150, 0.060}};
    glm::dmat3 unscaled;
    for (int i = 0; i < 3; ++i)
      unscaled[i] = Vec3(xy[i][0] / xy[i][1], 1.0, (1.0 - xy[i][0] - xy[i][1]) / xy[i][1]);
    const Vec3 scale = glm::inverse(unscaled) * Vec3(1.0);  // white: X = Y = Z = 1
    glm::dmat3 to_xyz;
    for (int i = 0; i < 3; ++i) to_xyz[i] = unscaled[i] * scale[i];
    return glm::inverse(to_xyz);
  }();
  return m;
}

}  // namespace

std::string spectrum_chromaticity(double lo, double hi, const std::vector<double>& values, Chromaticity* out) {
  std::array<double, kSamples> s{};
  const double last = static_cast<double>(values.size() - 1);
  for (int i = 0; i < kSamples; ++i) {
    const double nm = kCmfFirst + i;
    if (nm < lo || nm > hi) continue;
    const double at = std::min((nm - lo) / (hi - lo) * last, last);
    const size_t k = std::min(static_cast<size_t>(at), values.size() - 2);
    const double f = at - static_cast<double>(k);
    s[static_cast<size_t>(i)] = values[k] + f * (values[k + 1] - values[k]);
  }
  return chromaticity_of(xyz_of(s), out);
}

std::string black_body_chromaticity(double kelvin, Chromaticity* out) {
  // Planck's law up to a factor, in logarithms so that no temperature
  // overflows it: B ~ lambda^-5 / (exp(c2 / (lambda T)) - 1).
  constexpr double c2 = 1.438776877e-2;  // second radiation constant, m K
  std::array<double, kSamples> log_b{};
  double top = -INFINITY;
  for (int i = 0; i < kSamples; ++i) {
    const double lambda = (kCmfFirst + i) * 1e-9;
    const double x = c2 / (lambda * kelvin);
    if (!(x > 0.0) || !std::isfinite(x)) return "is outside the temperatures whose spectrum double precision holds";
    const double log_expm1 = x > 30.0 ? x + std::log1p(-std::exp(-x)) : std::log(std::expm1(x));
    log_b[static_cast<size_t>(i)] = -5.0 * std::log(lambda) - log_expm1;
    top = std::max(top, log_b[static_cast<size_t>(i)]);
  }
  std::array<double, kSamples> s{};
  for (size_t i = 0; i < kSamples; ++i) s[i] = std::exp(log_b[i] - top);
  return chromaticity_of(xyz_of(s), out);
}

Chromaticity mix(const std::vector<Chromaticity>& colors, const std::vector<double>& weights) {
  Vec3 xyz(0.0);
  for (size_t i = 0; i < colors.size(); ++i) {
    const Chromaticity& c = colors[i];
    xyz += weights[i] * Vec3(c.x / c.y, 1.0, (1.0 - c.x - c.y) / c.y);
  }
  Chromaticity out;
  chromaticity_of(xyz, &out);  // the weights' sum is positive (the reader checks): so is Y
  return out;
}

Rgb to_rgb(const Chromaticity& c, double luminance, bool* clipped) {
  *clipped = false;
  // Grey stays grey to the last bit: the matrices' rounding would tint it.
  if (std::abs(c.x - 1.0 / 3.0) <= 1e-12 && std::abs(c.y - 1.0 / 3.0) <= 1e-12) return Rgb(luminance);
  const Vec3 xyz(c.x / c.y * luminance, luminance, (1.0 - c.x - c.y) / c.y * luminance);
  Rgb rgb = xyz_to_rgb() * xyz;
  for (int k = 0; k < 3; ++k)
    if (rgb[k] < 0.0) {
      // A primary's own chromaticity leaves the other channels at rounding
      // noise: only more than that is outside the gamut.
      if (rgb[k] < -1e-12 * luminance) *clipped = true;
      rgb[k] = 0.0;
    }
  return rgb;
}

}  // namespace radmesh::internal::mgf
