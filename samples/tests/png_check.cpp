// Checks screenshots of the samples' pixel tests.
//   png_check BEFORE.png AFTER.png: prints the share of pixels that differ from the background colour in each image
//     and the share that differ between the two; exits 1 when an image is blank, the character's share is
//     implausible (outside 1%..70%), or the frame after the reach equals the frame before it (viewer smoke test).
//   png_check --same-picture A.png B.png: exits 1 when more than 0.1% of the pixels differ by more than 24 (sum over
//     RGB) or A is blank (the CPU and GPU lattice screenshots of the viewer and the ffd_lattice sample).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <string>

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

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::string(argv[1]) == "--same-picture") return same_picture(argv[2], argv[3]);
  if (argc != 3) {
    std::fprintf(stderr, "usage: png_check BEFORE.png AFTER.png | png_check --same-picture A.png B.png\n");
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
