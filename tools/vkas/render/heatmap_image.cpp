#include "heatmap_image.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace vkas_tool {
namespace {

// 3x5 pixel digits, one row of 3 bits per byte, top row first: enough for the legend's numbers.
const uint8_t kDigits[10][5] = {{7, 5, 5, 5, 7}, {2, 6, 2, 2, 7}, {7, 1, 7, 4, 7}, {7, 1, 7, 1, 7}, {5, 5, 7, 1, 1},
                                {7, 4, 7, 1, 7}, {7, 4, 7, 5, 7}, {7, 1, 1, 1, 1}, {7, 5, 7, 5, 7}, {7, 5, 7, 1, 7}};

void put(Image& img, int x, int y, const uint8_t c[3]) {
    if (x < 0 || y < 0 || x >= int(img.width) || y >= int(img.height)) return;
    uint8_t* p = &img.rgb[3 * (size_t(y) * img.width + size_t(x))];
    p[0] = c[0], p[1] = c[1], p[2] = c[2];
}

// Draws the decimal number at (x, y) (top left) with pixels `scale` wide, on a dark backing; returns its width.
int drawNumber(Image& img, int x, int y, uint32_t value, int scale, bool measureOnly = false) {
    const std::string s = std::to_string(value);
    const int w = int(s.size()) * 4 * scale - scale;
    if (measureOnly) return w;
    const uint8_t back[3] = {0, 0, 0}, ink[3] = {255, 255, 255};
    for (int yy = -scale; yy < 6 * scale; ++yy)
        for (int xx = -scale; xx < w + scale; ++xx) put(img, x + xx, y + yy, back);
    for (size_t i = 0; i < s.size(); ++i)
        for (int row = 0; row < 5; ++row)
            for (int col = 0; col < 3; ++col)
                if (kDigits[s[i] - '0'][row] & (4 >> col))
                    for (int a = 0; a < scale; ++a)
                        for (int b = 0; b < scale; ++b)
                            put(img, x + int(i) * 4 * scale + col * scale + b, y + row * scale + a, ink);
    return w;
}

}  // namespace

void viridis(float t, uint8_t rgb[3]) {
    // A polynomial fit of matplotlib's viridis (in sRGB): c0 + t (c1 + t (c2 + ...)).
    static const double c[7][3] = {{0.2777273272234177, 0.005407344544966578, 0.3340998053353061},
                                   {0.1050930431085774, 1.404613529898575, 1.384590162594685},
                                   {-0.3308618287255563, 0.214847559468213, 0.09509516302823659},
                                   {-4.634230498983486, -5.799100973351585, -19.33244095627987},
                                   {6.228269936347081, 14.17993336680509, 56.69055260068105},
                                   {4.776384997670288, -13.74514537774601, -65.35303263337234},
                                   {-5.435455855934631, 4.645852612178535, 26.3124352495832}};
    const double x = std::clamp(double(t), 0.0, 1.0);
    for (int k = 0; k < 3; ++k) {
        double v = c[6][k];
        for (int i = 5; i >= 0; --i) v = c[i][k] + x * v;
        rgb[k] = uint8_t(std::lround(std::clamp(v, 0.0, 1.0) * 255.0));
    }
}

Image heatmapImage(const std::vector<uint32_t>& values, uint32_t W, uint32_t H, uint32_t lo, uint32_t hi) {
    Image img;
    img.width = W, img.height = H;
    img.rgb.resize(size_t(W) * H * 3);
    const double span = hi > lo ? double(hi - lo) : 1.0;
    for (size_t p = 0; p < size_t(W) * H; ++p) viridis(float((double(values[p]) - lo) / span), &img.rgb[3 * p]);

    // The legend: a bar from lo (left) to hi (right) along the bottom, the two numbers above its ends.
    const int scale = H >= 240 ? 2 : 1;
    const int barH = std::max(3, int(H) / 30), margin = std::max(2, int(W) / 40);
    const int barY = int(H) - margin - barH, barX0 = margin, barX1 = int(W) - margin;
    if (barX1 - barX0 < 8 || barY < 8 * scale) return img;  // too small for a legend
    const uint8_t frame[3] = {0, 0, 0};
    for (int x = barX0 - 1; x <= barX1; ++x)
        for (int y = barY - 1; y <= barY + barH; ++y) {
            if (x < barX0 || x == barX1 || y < barY || y == barY + barH) {
                put(img, x, y, frame);
                continue;
            }
            uint8_t c[3];
            viridis(float(x - barX0) / float(barX1 - barX0 - 1), c);
            put(img, x, y, c);
        }
    const int textY = barY - 7 * scale;
    drawNumber(img, barX0 + scale, textY, lo, scale);
    drawNumber(img, barX1 - scale - drawNumber(img, 0, 0, hi, scale, true), textY, hi, scale);
    return img;
}

}  // namespace vkas_tool
