#include "Image.h"

#include <xmmintrin.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <stdexcept>

namespace {

typedef std::vector<uint8_t> Bytes;

[[noreturn]] void fail(const std::string& why) { throw std::runtime_error(why); }

uint32_t crc32(const uint8_t* p, size_t n) {
    static const std::vector<uint32_t> table = [] {  // thread-safe static init
        std::vector<uint32_t> t(256);
        for (uint32_t i = 0; i < 256; ++i) {
            uint32_t c = i;
            for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xedb88320u ^ (c >> 1) : c >> 1;
            t[i] = c;
        }
        return t;
    }();
    uint32_t c = 0xffffffffu;
    for (size_t i = 0; i < n; ++i) c = table[(c ^ p[i]) & 0xff] ^ (c >> 8);
    return c ^ 0xffffffffu;
}

uint32_t adler32(const Bytes& d) {
    uint32_t a = 1, b = 0;
    for (uint8_t v : d) { a = (a + v) % 65521; b = (b + a) % 65521; }
    return (b << 16) | a;
}

void put32(Bytes& out, uint32_t v) {  // PNG and zlib integers are big-endian
    for (int s = 24; s >= 0; s -= 8) out.push_back(uint8_t(v >> s));
}

uint32_t get32(const uint8_t* p) {
    return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3];
}

void putChunk(Bytes& png, const char* type, const Bytes& data) {
    put32(png, uint32_t(data.size()));
    size_t start = png.size();  // the CRC covers type and data, not length
    png.insert(png.end(), type, type + 4);
    png.insert(png.end(), data.begin(), data.end());
    put32(png, crc32(&png[start], png.size() - start));
}

// Bit-exact with the reference: cvttss2si yields INT_MIN for NaN, inf and
// out-of-range values, which the clamp then maps to 0.
uint8_t quantise(float c) {
    float v = c * 255.0f;
    int i = _mm_cvttss_si32(_mm_set_ss(v));
    return uint8_t(std::min(255, std::max(0, i)));
}

// Canonical Huffman code: count[len] codes of each length, symbols in code order.
struct Huffman {
    int count[16];
    std::vector<int> sym;
    Huffman(const uint8_t* len, int n) : sym(n) {
        std::fill(count, count + 16, 0);
        for (int i = 0; i < n; ++i) count[len[i]]++;
        int left = 1, offs[16] = {0};
        for (int l = 1; l < 16; ++l) {
            left = (left << 1) - count[l];
            if (left < 0) fail("over-subscribed Huffman code");
            if (l < 15) offs[l + 1] = offs[l] + count[l];
        }
        // Incomplete codes are allowed; hitting an unused code fails in decode().
        for (int i = 0; i < n; ++i) if (len[i]) sym[offs[len[i]]++] = i;
    }
};

// RFC 1951 inflate with a hard output cap, so corrupt input cannot run away.
class Inflater {
public:
    Inflater(const uint8_t* p, size_t n, size_t cap) : p_(p), n_(n), cap_(cap) {}

    Bytes run() {
        for (bool last = false; !last;) {
            last = bits(1);
            switch (bits(2)) {
                case 0: stored(); break;
                case 1: fixed(); break;
                case 2: dynamic(); break;
                default: fail("invalid deflate block type");
            }
        }
        return out_;
    }

private:
    const uint8_t* p_;
    size_t n_, pos_ = 0, cap_;
    uint32_t buf_ = 0;
    int cnt_ = 0;
    Bytes out_;

    int bits(int k) {  // deflate packs bits LSB first
        while (cnt_ < k) {
            if (pos_ >= n_) fail("compressed data truncated");
            buf_ |= uint32_t(p_[pos_++]) << cnt_;
            cnt_ += 8;
        }
        int v = int(buf_ & ((1u << k) - 1));
        buf_ >>= k;
        cnt_ -= k;
        return v;
    }

    void put(uint8_t b) {
        if (out_.size() >= cap_) fail("too much image data");
        out_.push_back(b);
    }

    int decode(const Huffman& h) {
        int code = 0, first = 0, index = 0;
        for (int l = 1; l < 16; ++l) {
            code |= bits(1);
            if (code - first < h.count[l]) return h.sym[index + code - first];
            index += h.count[l];
            first = (first + h.count[l]) << 1;
            code <<= 1;
        }
        fail("invalid Huffman code");
    }

    void stored() {
        buf_ = 0;  // at most 7 bits remain, all padding up to the byte boundary
        cnt_ = 0;
        int len = bits(16), nlen = bits(16);
        if (len != (~nlen & 0xffff)) fail("corrupt stored block length");
        if (n_ - pos_ < size_t(len)) fail("compressed data truncated");
        for (int i = 0; i < len; ++i) put(p_[pos_++]);
    }

    void fixed() {
        uint8_t len[288 + 30];
        std::fill(len, len + 144, 8);
        std::fill(len + 144, len + 256, 9);
        std::fill(len + 256, len + 280, 7);
        std::fill(len + 280, len + 288, 8);
        std::fill(len + 288, len + 318, 5);
        codes(Huffman(len, 288), Huffman(len + 288, 30));
    }

    void dynamic() {
        static const uint8_t order[19] = {16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15};
        int nlit = bits(5) + 257, ndist = bits(5) + 1, ncl = bits(4) + 4;
        if (nlit > 286 || ndist > 30) fail("bad dynamic block header");
        uint8_t cl[19] = {0}, len[286 + 30] = {0};
        for (int i = 0; i < ncl; ++i) cl[order[i]] = uint8_t(bits(3));
        Huffman clh(cl, 19);
        for (int i = 0; i < nlit + ndist;) {
            int s = decode(clh), rep, val = 0;
            if (s < 16) { len[i++] = uint8_t(s); continue; }
            if (s == 16) {
                if (i == 0) fail("repeat with no previous length");
                val = len[i - 1];
                rep = 3 + bits(2);
            } else {
                rep = s == 17 ? 3 + bits(3) : 11 + bits(7);
            }
            if (i + rep > nlit + ndist) fail("too many code lengths");
            while (rep--) len[i++] = uint8_t(val);
        }
        if (!len[256]) fail("no end-of-block code");
        codes(Huffman(len, nlit), Huffman(len + nlit, ndist));
    }

    void codes(const Huffman& lit, const Huffman& dist) {
        static const int lbase[29] = {3, 4, 5, 6, 7, 8, 9, 10, 11, 13, 15, 17, 19, 23, 27,
                                      31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
        static const int lext[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                     2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
        static const int dbase[30] = {1, 2, 3, 4, 5, 7, 9, 13, 17, 25, 33, 49, 65, 97, 129,
                                      193, 257, 385, 513, 769, 1025, 1537, 2049, 3073, 4097,
                                      6145, 8193, 12289, 16385, 24577};
        static const int dext[30] = {0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6,
                                     6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};
        for (;;) {
            int s = decode(lit);
            if (s < 256) { put(uint8_t(s)); continue; }
            if (s == 256) return;
            if ((s -= 257) >= 29) fail("invalid length code");
            int n = lbase[s] + bits(lext[s]);
            int d = decode(dist);
            if (d >= 30) fail("invalid distance code");
            size_t back = size_t(dbase[d] + bits(dext[d]));
            if (back > out_.size()) fail("distance too far back");
            while (n--) put(out_[out_.size() - back]);  // put() takes a copy
        }
    }
};

}  // namespace

Image::Image(int w, int h)
    : w_(std::max(w, 0)), h_(std::max(h, 0)), data_(size_t(w_) * h_ * 3, 0.0f) {}

void Image::setPixel(int x, int y, const Vector3f& c) {
    if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
    float* p = &data_[(size_t(y) * w_ + x) * 3];
    p[0] = c.x();
    p[1] = c.y();
    p[2] = c.z();
}

Vector3f Image::getPixel(int x, int y) const {
    if (w_ == 0 || h_ == 0) return Vector3f(0, 0, 0);
    x = std::min(std::max(x, 0), w_ - 1);
    y = std::min(std::max(y, 0), h_ - 1);
    const float* p = &data_[(size_t(y) * w_ + x) * 3];
    return Vector3f(p[0], p[1], p[2]);
}

bool Image::savePNG(const std::string& path) const {
    if (w_ == 0 || h_ == 0) return false;  // PNG forbids empty images
    Bytes raw;
    raw.reserve(size_t(h_) * (1 + size_t(w_) * 3));
    for (int y = h_ - 1; y >= 0; --y) {  // the file's first row is the top
        raw.push_back(0);                 // filter type None
        const float* row = &data_[size_t(y) * w_ * 3];
        for (int i = 0; i < w_ * 3; ++i) raw.push_back(quantise(row[i]));
    }
    Bytes z = {0x78, 0x01};  // deflate, 32K window, no dictionary
    for (size_t pos = 0;;) {  // stored blocks: no compression needed
        size_t n = std::min<size_t>(raw.size() - pos, 65535);
        bool last = pos + n == raw.size();
        z.insert(z.end(), {uint8_t(last), uint8_t(n), uint8_t(n >> 8), uint8_t(~n), uint8_t(~n >> 8)});
        z.insert(z.end(), raw.begin() + pos, raw.begin() + pos + n);
        if (last) break;
        pos += n;
    }
    put32(z, adler32(raw));
    Bytes ihdr;
    put32(ihdr, uint32_t(w_));
    put32(ihdr, uint32_t(h_));
    ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0});  // 8-bit RGB, deflate, no interlace
    Bytes png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    putChunk(png, "IHDR", ihdr);
    putChunk(png, "IDAT", z);
    putChunk(png, "IEND", Bytes());

    FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return false;
    bool ok = std::fwrite(png.data(), 1, png.size(), f) == png.size();
    return std::fclose(f) == 0 && ok;
}

Image* Image::loadPNG(const std::string& path) {
    try {
        FILE* f = std::fopen(path.c_str(), "rb");
        if (!f) fail("cannot open file");
        Bytes file;
        uint8_t buf[65536];
        for (size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;) file.insert(file.end(), buf, buf + n);
        bool readError = std::ferror(f);
        std::fclose(f);
        if (readError) fail("read error");

        static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
        if (file.size() < 8 || !std::equal(sig, sig + 8, file.begin())) fail("not a PNG file");
        uint32_t w = 0, h = 0;
        int type = -1;
        Bytes idat, plte;
        for (size_t pos = 8;;) {
            if (file.size() - pos < 12) fail("file truncated");
            uint32_t len = get32(&file[pos]);
            if (len > file.size() - pos - 12) fail("file truncated");
            const uint8_t* tag = &file[pos + 4];
            const uint8_t* d = tag + 4;
            std::string name(tag, tag + 4);
            for (char& c : name) if (!std::isalpha((unsigned char)c)) c = '?';  // printable in messages
            if (crc32(tag, size_t(len) + 4) != get32(d + len)) fail("CRC mismatch in " + name + " chunk");
            pos += 12 + len;
            if (name == "IHDR") {
                if (len != 13) fail("bad IHDR chunk");
                w = get32(d), h = get32(d + 4), type = d[9];
                if (w == 0 || h == 0 || uint64_t(w) * h > (1u << 28)) fail("bad or huge image size");
                if (d[8] != 8) fail("bit depth " + std::to_string(d[8]) + " not supported (only 8)");
                if (type > 6 || type == 1 || type == 5) fail("bad colour type");
                if (d[10] || d[11]) fail("unknown compression or filter method");
                if (d[12]) fail("interlaced PNGs are not supported");
            } else if (type < 0) {
                fail("IHDR chunk missing");
            } else if (name == "PLTE") {
                plte.assign(d, d + len);
            } else if (name == "IDAT") {
                idat.insert(idat.end(), d, d + len);
            } else if (name == "IEND") {
                break;
            } else if (!(tag[0] & 0x20)) {  // lower-case first letter = safe to skip
                fail("unknown critical chunk " + name);
            }
        }
        if (type == 3 && plte.empty()) fail("palette missing");

        static const int channels[7] = {1, 0, 3, 1, 2, 0, 4};
        const size_t ch = size_t(channels[type]), stride = w * ch;
        if (idat.size() < 2 || (idat[0] & 0x0f) != 8 || (idat[0] << 8 | idat[1]) % 31 || (idat[1] & 0x20))
            fail("bad zlib header");
        Bytes raw = Inflater(idat.data() + 2, idat.size() - 2, h * (stride + 1)).run();
        if (raw.size() != h * (stride + 1)) fail("image data truncated");

        std::unique_ptr<Image> img(new Image(int(w), int(h)));
        Bytes zero(stride, 0);
        for (size_t r = 0; r < h; ++r) {
            uint8_t* cur = &raw[r * (stride + 1)];
            const int filter = *cur++;
            const uint8_t* prev = r ? cur - (stride + 1) : zero.data();
            if (filter > 4) fail("bad row filter type");
            for (size_t i = 0; i < stride; ++i) {  // undo filtering in place
                int a = i >= ch ? cur[i - ch] : 0, b = prev[i], c = i >= ch ? prev[i - ch] : 0;
                int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
                int pred[5] = {0, a, b, (a + b) / 2, pa <= pb && pa <= pc ? a : pb <= pc ? b : c};
                cur[i] = uint8_t(cur[i] + pred[filter]);
            }
            float* out = &img->data_[(h - 1 - r) * w * 3];  // file row 0 is the top
            for (size_t x = 0; x < w; ++x) {
                const uint8_t* s = cur + x * ch;
                if (type == 3) {
                    if (size_t(s[0]) * 3 + 3 > plte.size()) fail("palette index out of range");
                    s = &plte[s[0] * 3];
                }
                const bool grey = type == 0 || type == 4;
                for (int k = 0; k < 3; ++k) out[x * 3 + k] = float(s[grey ? 0 : k]) / 255.0f;
            }
        }
        return img.release();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "loadPNG: %s: %s\n", path.c_str(), e.what());
        return nullptr;
    }
}
