// Checks screenshots of the samples' pixel tests.
//   png_check BEFORE.png AFTER.png: prints the share of pixels that differ from the background colour in each image
//     and the share that differ between the two; exits 1 when an image is blank, the character's share is
//     implausible (outside 1%..70%), or the frame after the reach equals the frame before it (viewer smoke test).
//   png_check --same-picture A.png B.png: exits 1 when more than 0.1% of the pixels differ by more than 24 (sum over
//     RGB) or A is blank (the CPU and GPU lattice screenshots of the viewer and the ffd_lattice sample).
//   png_check --bbox IMAGE [--height MIN,MAX] [--width MIN,MAX] [--floor-row ROW]: the silhouette's box (the pixels
//     that differ from the top-left corner's colour, the background of a bare frame): prints its rows and columns and
//     the share of the image's height and width it spans; exits 1 when the image is blank, the silhouette touches the
//     top or bottom border (cut off), its height is outside [MIN, MAX] of the image's (default 0.35, 0.95), its width
//     outside --width's (default: not checked; a figure lying down fills the width, not the height), or, with ROW (the
//     viewer's "floor_row": the floor's row under the character's lowest point), its lowest row is more than 3% of
//     the image's height away from it (the character floats above the floor or sinks into it).
//   png_check --colours IMAGE: of the pixels that differ from the top-left corner's colour (the background of a bare
//     frame), the shares whose red, green or blue channel exceeds both others by more than 24, as a JSON line
//     {"pixels": N, "red": R, "green": G, "blue": B} (the viewer's weight map: blue 0, green 0.5, red 1).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <string>
#include <vector>

#include <stb/stb_image.h>

namespace {

struct Image {
  int w = 0, h = 0;
  unsigned char* rgb = nullptr;
};

Image load(const char* path) {
  Image im;
  int channels = 0;
  im.rgb = stbi_load(path, &im.w, &im.h, &channels, 3);
  if (!im.rgb) {
    std::fprintf(stderr, "png_check: cannot read %s: %s\n", path, stbi_failure_reason());
    std::exit(1);
  }
  return im;
}

bool differs(const unsigned char* a, const unsigned char* b) {
  return std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]) > 24;
}

double coverage(const Image& im) {
  const unsigned char* background = im.rgb;  // the top-left corner is background in a bare frame
  long n = 0;
  for (long i = 0; i < long(im.w) * im.h; ++i) n += differs(im.rgb + 3 * i, background);
  return double(n) / (double(im.w) * im.h);
}

int same_picture(const char* path_a, const char* path_b) {
  const Image a = load(path_a), b = load(path_b);
  if (a.w != b.w || a.h != b.h) {
    std::printf("FAIL: the images differ in size\n");
    return 1;
  }
  const long pixels = long(a.w) * a.h;
  long differing = 0;
  for (long i = 0; i < pixels; ++i) differing += differs(a.rgb + 3 * i, b.rgb + 3 * i);
  const double share = double(differing) / double(pixels), covered = coverage(a);
  const bool ok = share <= 1e-3 && covered > 0.01;
  std::printf("%s %ld of %ld pixels differ (%.4f%%); %.1f%% of the first image is not background\n",
              ok ? "ok  " : "FAIL", differing, pixels, 100.0 * share, 100.0 * covered);
  return ok ? 0 : 1;
}

const char* usage =
    "usage: png_check BEFORE.png AFTER.png | png_check --same-picture A.png B.png\n"
    "       png_check --bbox IMAGE.png [--height MIN,MAX] [--width MIN,MAX] [--floor-row ROW]\n"
    "       png_check --colours IMAGE.png\n";

int colours(const char* path) {
  const Image im = load(path);
  long pixels = 0, dominant[3] = {0, 0, 0};
  for (long i = 0; i < long(im.w) * im.h; ++i) {
    const unsigned char* p = im.rgb + 3 * i;
    if (!differs(p, im.rgb)) continue;
    ++pixels;
    for (int c = 0; c < 3; ++c)
      if (p[c] > p[(c + 1) % 3] + 24 && p[c] > p[(c + 2) % 3] + 24) ++dominant[c];
  }
  stbi_image_free(im.rgb);
  const double n = double(std::max(1L, pixels));
  std::printf("{\"pixels\": %ld, \"red\": %.6f, \"green\": %.6f, \"blue\": %.6f}\n", pixels, double(dominant[0]) / n,
              double(dominant[1]) / n, double(dominant[2]) / n);
  return pixels > 0 ? 0 : 1;
}

int bbox(const std::vector<std::string>& args) {
  double min_height = 0.35, max_height = 0.95, min_width = 0.0, max_width = 1.0, floor_row = -1.0;
  for (std::size_t i = 1; i < args.size(); i += 2) {
    char tail = 0;
    const char* value = i + 1 < args.size() ? args[i + 1].c_str() : "";
    if (args[i] == "--height" && std::sscanf(value, "%lf,%lf%c", &min_height, &max_height, &tail) == 2) continue;
    if (args[i] == "--width" && std::sscanf(value, "%lf,%lf%c", &min_width, &max_width, &tail) == 2) continue;
    if (args[i] == "--floor-row" && std::sscanf(value, "%lf%c", &floor_row, &tail) == 1) continue;
    std::fprintf(stderr, "png_check: --bbox: bad option '%s %s'\n%s", args[i].c_str(), value, usage);
    return 2;
  }
  const Image im = load(args[0].c_str());
  int top = im.h, bottom = -1, left = im.w, right = -1;
  for (int y = 0; y < im.h; ++y)
    for (int x = 0; x < im.w; ++x)
      if (differs(im.rgb + 3 * (long(y) * im.w + x), im.rgb)) {
        top = std::min(top, y), bottom = std::max(bottom, y);
        left = std::min(left, x), right = std::max(right, x);
      }
  if (bottom < 0) {
    std::printf("FAIL %s: blank\n", args[0].c_str());
    return 1;
  }
  const double height = double(bottom - top + 1) / im.h, width = double(right - left + 1) / im.w;
  std::printf("%s: rows %d..%d (%.1f%% of the height), columns %d..%d (%.1f%% of the width)", args[0].c_str(), top,
              bottom, 100.0 * height, left, right, 100.0 * width);
  if (floor_row >= 0.0) std::printf(", floor at row %.1f", floor_row);
  std::printf("\n");
  bool ok = true;
  if (top == 0 || bottom == im.h - 1) ok = false, std::printf("FAIL: cut off at the %s\n", top == 0 ? "top" : "bottom");
  if (height < min_height || height > max_height)
    ok = false, std::printf("FAIL: the height is outside %.0f%%..%.0f%%\n", 100.0 * min_height, 100.0 * max_height);
  if (width < min_width || width > max_width)
    ok = false, std::printf("FAIL: the width is outside %.0f%%..%.0f%%\n", 100.0 * min_width, 100.0 * max_width);
  if (floor_row >= 0.0 && std::abs(bottom - floor_row) > 0.03 * im.h)
    ok = false, std::printf("FAIL: the lowest row is %.1f rows %s the floor's\n", std::abs(bottom - floor_row),
                            bottom < floor_row ? "above" : "below");
  return ok ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::string(argv[1]) == "--same-picture") return same_picture(argv[2], argv[3]);
  if (argc == 3 && std::string(argv[1]) == "--colours") return colours(argv[2]);
  if (argc >= 3 && std::string(argv[1]) == "--bbox") return bbox(std::vector<std::string>(argv + 2, argv + argc));
  if (argc != 3) {
    std::fprintf(stderr, "%s", usage);
    return 2;
  }
  const Image before = load(argv[1]), after = load(argv[2]);
  if (before.w != after.w || before.h != after.h) {
    std::fprintf(stderr, "png_check: the images differ in size\n");
    return 1;
  }
  long changed = 0;
  for (long i = 0; i < long(before.w) * before.h; ++i) changed += differs(before.rgb + 3 * i, after.rgb + 3 * i);
  const double cover_before = coverage(before), cover_after = coverage(after);
  const double change = double(changed) / (double(before.w) * before.h);
  std::printf("character covers %.1f%% before and %.1f%% after the reach; %.2f%% of pixels changed\n",
              100 * cover_before, 100 * cover_after, 100 * change);
  bool ok = true;
  for (double c : {cover_before, cover_after})
    if (c < 0.01 || c > 0.70) ok = false, std::fprintf(stderr, "png_check: implausible coverage %.3f\n", c);
  if (change < 0.002) ok = false, std::fprintf(stderr, "png_check: the reach changed nothing\n");
  return ok ? 0 : 1;
}
