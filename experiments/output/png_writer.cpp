#include "experiments/output/png_writer.hpp"

#include <png.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "experiments/output/output_file.hpp"

namespace hooke {

namespace {

struct Image {
  int w, h;
  std::vector<float> rgb;  // linear [0, 1], white background
  Image(int w_, int h_) : w(w_), h(h_), rgb(size_t(3) * w_ * h_, 1.0f) {}
  void blend(int x, int y, const float c[3], float a) {
    if (x < 0 || y < 0 || x >= w || y >= h || a <= 0.0f) return;
    float* p = &rgb[size_t(3) * (size_t(y) * w + x)];
    for (int k = 0; k < 3; ++k) p[k] = p[k] * (1.0f - a) + c[k] * a;
  }
  // Splat a sample at sub-pixel (fx, fy) with bilinear weights: cheap anti-aliasing.
  void splat(double fx, double fy, const float c[3], float a) {
    const int x0 = int(std::floor(fx)), y0 = int(std::floor(fy));
    const float tx = float(fx - x0), ty = float(fy - y0);
    blend(x0, y0, c, a * (1 - tx) * (1 - ty));
    blend(x0 + 1, y0, c, a * tx * (1 - ty));
    blend(x0, y0 + 1, c, a * (1 - tx) * ty);
    blend(x0 + 1, y0 + 1, c, a * tx * ty);
  }
  void line(double x0, double y0, double x1, double y1, const float c[3]) {
    const double len = std::hypot(x1 - x0, y1 - y0);
    const int steps = std::max(1, int(std::ceil(len * 2.0)));
    for (int k = 0; k <= steps; ++k) {
      const double t = double(k) / steps;
      splat(x0 + t * (x1 - x0), y0 + t * (y1 - y0), c, 0.6f);
    }
  }
};

/// libpng's error handler without its message on stderr: the OutputError thrown after the
/// longjmp names the file and the OS reason.
extern "C" void on_png_error(png_structp png, png_const_charp) { png_longjmp(png, 1); }
extern "C" void on_png_warning(png_structp, png_const_charp) {}

}  // namespace

void write_png_picture(const std::string& path, const State& s, const std::vector<char>& pinned,
                       const std::vector<std::array<int, 2>>& edges,
                       const std::vector<double>& rest, int width, int height,
                       double max_strain_colour) {
  const Index n = s.num_particles();
  const double az = 30.0 * M_PI / 180.0, el = 20.0 * M_PI / 180.0;
  // Screen axes of an orthographic camera orbiting the y axis.
  const Vec3 right(std::cos(az), 0.0, -std::sin(az));
  const Vec3 fwd(std::sin(az) * std::cos(el), -std::sin(el), std::cos(az) * std::cos(el));
  const Vec3 up = right.cross(fwd).normalized() * -1.0;
  std::vector<double> u(static_cast<size_t>(n)), w(static_cast<size_t>(n));
  double umin = 1e300, umax = -1e300, wmin = 1e300, wmax = -1e300;
  for (Index i = 0; i < n; ++i) {
    const Vec3 p = s.x.segment<3>(3 * i);
    u[size_t(i)] = p.dot(right);
    w[size_t(i)] = p.dot(up);
    umin = std::min(umin, u[size_t(i)]), umax = std::max(umax, u[size_t(i)]);
    wmin = std::min(wmin, w[size_t(i)]), wmax = std::max(wmax, w[size_t(i)]);
  }
  const double margin = 40.0;
  const double span = std::max({umax - umin, wmax - wmin, 1e-12});
  const double scale = std::min((width - 2 * margin) / std::max(umax - umin, span * 1e-3),
                                (height - 2 * margin) / std::max(wmax - wmin, span * 1e-3));
  const double cu = 0.5 * (umin + umax), cw = 0.5 * (wmin + wmax);
  auto sx = [&](Index i) { return 0.5 * width + scale * (u[size_t(i)] - cu); };
  auto sy = [&](Index i) { return 0.5 * height - scale * (w[size_t(i)] - cw); };

  Image img(width, height);
  for (size_t e = 0; e < edges.size(); ++e) {
    const int a = edges[e][0], b = edges[e][1];
    const double l = (s.x.segment<3>(3 * a) - s.x.segment<3>(3 * b)).norm();
    const double strain = rest[e] > 0 ? (l - rest[e]) / rest[e] : 0.0;
    const float t = float(std::clamp(strain / max_strain_colour, 0.0, 1.0));
    const float c[3] = {0.1f + 0.8f * t, 0.3f * (1 - t), 0.8f * (1 - t)};
    img.line(sx(a), sy(a), sx(b), sy(b), c);
  }
  const float black[3] = {0, 0, 0};
  for (Index i = 0; i < n; ++i)
    if (pinned[size_t(i)])
      for (int dy = -3; dy <= 3; ++dy)
        for (int dx = -3; dx <= 3; ++dx)
          if (dx * dx + dy * dy <= 9) img.blend(int(sx(i)) + dx, int(sy(i)) + dy, black, 1.0f);

  OutputFile file = OutputFile::replace(path);
  std::vector<png_byte> row(size_t(3) * width);  // before setjmp: a longjmp skips no destructor
  png_structp png =
      png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, on_png_error, on_png_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info || setjmp(png_jmpbuf(png))) {
    const int err = errno;  // a failed write (full disk) is the usual cause: name it
    png_destroy_write_struct(&png, &info);
    throw OutputError(path, "write", err);
  }
  png_init_io(png, file.get());
  png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < height; ++y) {
    for (int k = 0; k < 3 * width; ++k)
      row[size_t(k)] = png_byte(
          std::lround(255.0f * std::clamp(img.rgb[size_t(3) * y * width + k], 0.0f, 1.0f)));
    png_write_row(png, row.data());
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  file.commit();
}

}  // namespace hooke
