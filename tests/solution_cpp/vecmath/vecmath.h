// A small vecmath in the shape of the starter's: float vectors and matrices whose operations
// round exactly as the course's (sums left to right, three divisions for v / s, cofactor
// inverses without a singularity test).
#ifndef VECMATH_H
#define VECMATH_H

#include <cmath>

class Vector2f {
public:
    Vector2f(float x = 0, float y = 0) { m[0] = x; m[1] = y; }
    float x() const { return m[0]; }
    float y() const { return m[1]; }
    float& operator[](int i) { return m[i]; }
    float operator[](int i) const { return m[i]; }
private:
    float m[2];
};

class Vector3f {
public:
    Vector3f(float v = 0) { m[0] = m[1] = m[2] = v; }
    Vector3f(float x, float y, float z) { m[0] = x; m[1] = y; m[2] = z; }
    float x() const { return m[0]; }
    float y() const { return m[1]; }
    float z() const { return m[2]; }
    float& operator[](int i) { return m[i]; }
    float operator[](int i) const { return m[i]; }
    float absSquared() const { return dot(*this, *this); }
    float abs() const { return std::sqrt(absSquared()); }
    Vector3f normalized() const { float n = abs(); return Vector3f(m[0] / n, m[1] / n, m[2] / n); }
    void normalize() { *this = normalized(); }
    Vector3f& operator+=(const Vector3f& v) { m[0] += v.m[0]; m[1] += v.m[1]; m[2] += v.m[2]; return *this; }
    Vector3f& operator-=(const Vector3f& v) { m[0] -= v.m[0]; m[1] -= v.m[1]; m[2] -= v.m[2]; return *this; }
    Vector3f& operator*=(float f) { m[0] *= f; m[1] *= f; m[2] *= f; return *this; }

    static float dot(const Vector3f& a, const Vector3f& b) {
        return (a.m[0] * b.m[0] + a.m[1] * b.m[1]) + a.m[2] * b.m[2];
    }
    static Vector3f cross(const Vector3f& a, const Vector3f& b) {
        return Vector3f(a.m[1] * b.m[2] - a.m[2] * b.m[1], a.m[2] * b.m[0] - a.m[0] * b.m[2],
                        a.m[0] * b.m[1] - a.m[1] * b.m[0]);
    }
private:
    float m[3];
};

inline Vector3f operator+(const Vector3f& a, const Vector3f& b) { return Vector3f(a[0] + b[0], a[1] + b[1], a[2] + b[2]); }
inline Vector3f operator-(const Vector3f& a, const Vector3f& b) { return Vector3f(a[0] - b[0], a[1] - b[1], a[2] - b[2]); }
inline Vector3f operator-(const Vector3f& a) { return Vector3f(-a[0], -a[1], -a[2]); }
// component-wise product (the starter's operator* of two vectors)
inline Vector3f operator*(const Vector3f& a, const Vector3f& b) { return Vector3f(a[0] * b[0], a[1] * b[1], a[2] * b[2]); }
inline Vector3f operator*(float f, const Vector3f& v) { return Vector3f(f * v[0], f * v[1], f * v[2]); }
inline Vector3f operator*(const Vector3f& v, float f) { return Vector3f(v[0] * f, v[1] * f, v[2] * f); }
inline Vector3f operator/(const Vector3f& v, float f) { return Vector3f(v[0] / f, v[1] / f, v[2] / f); }

class Vector4f {
public:
    Vector4f(float x = 0, float y = 0, float z = 0, float w = 0) { m[0] = x; m[1] = y; m[2] = z; m[3] = w; }
    Vector4f(const Vector3f& v, float w) { m[0] = v[0]; m[1] = v[1]; m[2] = v[2]; m[3] = w; }
    float x() const { return m[0]; }
    float y() const { return m[1]; }
    float z() const { return m[2]; }
    float w() const { return m[3]; }
    Vector3f xyz() const { return Vector3f(m[0], m[1], m[2]); }
    float& operator[](int i) { return m[i]; }
    float operator[](int i) const { return m[i]; }
private:
    float m[4];
};

class Matrix3f {
public:
    explicit Matrix3f(float fill = 0) { for (int i = 0; i < 9; ++i) m[i] = fill; }
    // columns, as the starter's constructor takes them
    Matrix3f(const Vector3f& c0, const Vector3f& c1, const Vector3f& c2) {
        for (int i = 0; i < 3; ++i) { (*this)(i, 0) = c0[i]; (*this)(i, 1) = c1[i]; (*this)(i, 2) = c2[i]; }
    }
    float& operator()(int i, int j) { return m[j * 3 + i]; }
    float operator()(int i, int j) const { return m[j * 3 + i]; }
    static float determinant2x2(float a, float b, float c, float d) { return a * d - b * c; }
    Matrix3f transposed() const {
        Matrix3f t;
        for (int i = 0; i < 3; ++i) for (int j = 0; j < 3; ++j) t(i, j) = (*this)(j, i);
        return t;
    }
    Matrix3f inverse() const {
        const Matrix3f& a = *this;
        float c00 = determinant2x2(a(1, 1), a(1, 2), a(2, 1), a(2, 2));
        float c01 = -determinant2x2(a(1, 0), a(1, 2), a(2, 0), a(2, 2));
        float c02 = determinant2x2(a(1, 0), a(1, 1), a(2, 0), a(2, 1));
        float c10 = -determinant2x2(a(0, 1), a(0, 2), a(2, 1), a(2, 2));
        float c11 = determinant2x2(a(0, 0), a(0, 2), a(2, 0), a(2, 2));
        float c12 = -determinant2x2(a(0, 0), a(0, 1), a(2, 0), a(2, 1));
        float c20 = determinant2x2(a(0, 1), a(0, 2), a(1, 1), a(1, 2));
        float c21 = -determinant2x2(a(0, 0), a(0, 2), a(1, 0), a(1, 2));
        float c22 = determinant2x2(a(0, 0), a(0, 1), a(1, 0), a(1, 1));
        float r = 1.0f / ((a(0, 0) * c00 + a(0, 1) * c01) + a(0, 2) * c02);
        Matrix3f inv;
        inv(0, 0) = c00 * r; inv(0, 1) = c10 * r; inv(0, 2) = c20 * r;
        inv(1, 0) = c01 * r; inv(1, 1) = c11 * r; inv(1, 2) = c21 * r;
        inv(2, 0) = c02 * r; inv(2, 1) = c12 * r; inv(2, 2) = c22 * r;
        return inv;
    }
private:
    float m[9];  // column-major
};

inline Vector3f operator*(const Matrix3f& a, const Vector3f& v) {
    Vector3f r;
    for (int i = 0; i < 3; ++i) r[i] = (a(i, 0) * v[0] + a(i, 1) * v[1]) + a(i, 2) * v[2];
    return r;
}

class Matrix4f {
public:
    explicit Matrix4f(float fill = 0) { for (int i = 0; i < 16; ++i) m[i] = fill; }
    float& operator()(int i, int j) { return m[j * 4 + i]; }
    float operator()(int i, int j) const { return m[j * 4 + i]; }
    static Matrix4f identity() { Matrix4f a; for (int i = 0; i < 4; ++i) a(i, i) = 1; return a; }
    Matrix3f getSubmatrix3x3(int i0, int j0) const {
        Matrix3f s;
        for (int i = 0; i < 3; ++i) for (int j = 0; j < 3; ++j) s(i, j) = (*this)(i0 + i, j0 + j);
        return s;
    }
    static Matrix4f translation(float x, float y, float z) {
        Matrix4f a = identity(); a(0, 3) = x; a(1, 3) = y; a(2, 3) = z; return a;
    }
    static Matrix4f scaling(float x, float y, float z) {
        Matrix4f a = identity(); a(0, 0) = x; a(1, 1) = y; a(2, 2) = z; return a;
    }
    static Matrix4f uniformScaling(float s) { return scaling(s, s, s); }
    // cos and sin of the float angle in double, rounded to float
    static Matrix4f rotateX(float rad) {
        float c = (float)std::cos((double)rad), s = (float)std::sin((double)rad);
        Matrix4f a = identity(); a(1, 1) = c; a(1, 2) = -s; a(2, 1) = s; a(2, 2) = c; return a;
    }
    static Matrix4f rotateY(float rad) {
        float c = (float)std::cos((double)rad), s = (float)std::sin((double)rad);
        Matrix4f a = identity(); a(0, 0) = c; a(0, 2) = s; a(2, 0) = -s; a(2, 2) = c; return a;
    }
    static Matrix4f rotateZ(float rad) {
        float c = (float)std::cos((double)rad), s = (float)std::sin((double)rad);
        Matrix4f a = identity(); a(0, 0) = c; a(0, 1) = -s; a(1, 0) = s; a(1, 1) = c; return a;
    }
    static Matrix4f rotation(const Vector3f& axis, float rad) {
        Vector3f n = axis.normalized();
        float c = (float)std::cos((double)rad), s = (float)std::sin((double)rad);
        float x = n[0], y = n[1], z = n[2], oc = 1.0f - c;
        Matrix4f a = identity();
        a(0, 0) = c + x * x * oc;     a(0, 1) = x * y * oc - z * s; a(0, 2) = x * z * oc + y * s;
        a(1, 0) = y * x * oc + z * s; a(1, 1) = c + y * y * oc;     a(1, 2) = y * z * oc - x * s;
        a(2, 0) = z * x * oc - y * s; a(2, 1) = z * y * oc + x * s; a(2, 2) = c + z * z * oc;
        return a;
    }
    Matrix4f inverse() const {
        const Matrix4f& e = *this;
        float c[4][4];
        for (int i = 0; i < 4; ++i) {
            for (int j = 0; j < 4; ++j) {
                float a[3][3];
                for (int r = 0; r < 3; ++r)
                    for (int s = 0; s < 3; ++s) a[r][s] = e((i + 1 + r) % 4, (j + 1 + s) % 4);
                float minor = ((a[1][1] * a[2][2] - a[1][2] * a[2][1]) * a[0][0]
                               - (a[1][0] * a[2][2] - a[1][2] * a[2][0]) * a[0][1])
                              + (a[1][0] * a[2][1] - a[1][1] * a[2][0]) * a[0][2];
                c[i][j] = ((i + j) % 2 == 0) ? minor : -minor;
            }
        }
        float det = ((e(0, 0) * c[0][0] + e(0, 1) * c[0][1]) + e(0, 2) * c[0][2]) + e(0, 3) * c[0][3];
        float r = 1.0f / det;
        Matrix4f inv;
        for (int i = 0; i < 4; ++i) for (int j = 0; j < 4; ++j) inv(i, j) = c[j][i] * r;
        return inv;
    }
private:
    float m[16];  // column-major
};

inline Matrix4f operator*(const Matrix4f& a, const Matrix4f& b) {
    Matrix4f p;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            p(i, j) = ((a(i, 0) * b(0, j) + a(i, 1) * b(1, j)) + a(i, 2) * b(2, j)) + a(i, 3) * b(3, j);
    return p;
}

inline Vector4f operator*(const Matrix4f& a, const Vector4f& v) {
    Vector4f r;
    for (int i = 0; i < 4; ++i) r[i] = ((a(i, 0) * v[0] + a(i, 1) * v[1]) + a(i, 2) * v[2]) + a(i, 3) * v[3];
    return r;
}

#endif
