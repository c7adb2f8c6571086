// Checks viewer screenshots for the smoke test: png_check BEFORE.png AFTER.png
// Prints the share of pixels that differ from the background colour in each image and the share that differ
// between the two; exits 1 when an image is blank, the character's share is implausible (outside 1%..70%), or the
// frame after the reach equals the frame before it.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>

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

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: png_check BEFORE.png AFTER.png\n");
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
