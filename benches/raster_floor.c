// The raster floor of `make bench` (docs/benchmarks.md): six-view orthographic rasterization of an
// OBJ into an R^3 RGBA8 slice stack, one thread, scalar, occupancy only. Per pixel centre (one sample
// per voxel column): barycentrics, depth -> slice index, UV interpolation, nearest texel fetch from a
// 512x512 RGBA test texture (opaque, so the alpha test never discards), alpha test, store. No
// coverage samples, compositing, MIP, combine or output file: what no six-direction voxelizer can
// beat by much. Reports fragments/s excluding OBJ parsing.
// Build: cc -O3 -march=native -o raster_floor raster_floor.c    Usage: raster_floor mesh.obj R
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
static double now(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec + t.tv_nsec * 1e-9; }
static inline float minf(float a, float b) { return a < b ? a : b; }
static inline float maxf(float a, float b) { return a > b ? a : b; }
int main(int argc, char **argv) {
    FILE *f = fopen(argv[1], "r");
    int R = atoi(argv[2]);
    size_t cv = 1 << 20, ct = 1 << 20, cf = 1 << 20, nv = 0, nt = 0, nf = 0;
    float *V = malloc(cv * 12), *T = malloc(ct * 8);
    int *F = malloc(cf * 24);
    char line[512];
    double tp = now();
    while (fgets(line, sizeof line, f)) {
        if (line[0] == 'v' && line[1] == ' ') {
            if (nv == cv) V = realloc(V, (cv *= 2) * 12);
            sscanf(line + 2, "%f %f %f", &V[nv * 3], &V[nv * 3 + 1], &V[nv * 3 + 2]); nv++;
        } else if (line[0] == 'v' && line[1] == 't') {
            if (nt == ct) T = realloc(T, (ct *= 2) * 8);
            sscanf(line + 3, "%f %f", &T[nt * 2], &T[nt * 2 + 1]); nt++;
        } else if (line[0] == 'f' && line[1] == ' ') {
            if (nf == cf) F = realloc(F, (cf *= 2) * 24);
            int a = 1, b = 1, c = 1, ta = 1, tb = 1, tc = 1, n;
            // v/t/n, v/t or v (triangles; the first three corners of anything else)
            if (sscanf(line + 2, "%d/%d/%d %d/%d/%d %d/%d/%d", &a, &ta, &n, &b, &tb, &n, &c, &tc, &n) != 9 &&
                sscanf(line + 2, "%d/%d %d/%d %d/%d", &a, &ta, &b, &tb, &c, &tc) != 6)
                sscanf(line + 2, "%d %d %d", &a, &b, &c);
            int *q = F + nf * 6; q[0] = a - 1; q[1] = b - 1; q[2] = c - 1; q[3] = ta - 1; q[4] = tb - 1; q[5] = tc - 1; nf++;
        }
    }
    if (nt == 0) { T = calloc(2, 4); nt = 1; }
    double tparse = now() - tp;
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
    for (size_t i = 0; i < nv; i++) for (int k = 0; k < 3; k++) { lo[k] = minf(lo[k], V[i * 3 + k]); hi[k] = maxf(hi[k], V[i * 3 + k]); }
    float ext = maxf(hi[0] - lo[0], maxf(hi[1] - lo[1], hi[2] - lo[2]));
    float s = (R - 0.001f) / ext;
    for (size_t i = 0; i < nv; i++) for (int k = 0; k < 3; k++) V[i * 3 + k] = (V[i * 3 + k] - lo[k]) * s;
    const int TW = 512;
    uint32_t *tex = malloc(TW * TW * 4);
    for (int i = 0; i < TW * TW; i++) tex[i] = 0xff000000u | (uint32_t)(i * 2654435761u >> 8);
    size_t nvox = (size_t)R * R * R;
    uint32_t *vox = malloc(nvox * 4);
    long frags = 0;
    double t0 = now();
    memset(vox, 0, nvox * 4);  // the slice stack is cleared once per bake (counted)
    for (int view = 0; view < 6; view++) {
        int az = view % 3, ax = (az + 1) % 3, ay = (az + 2) % 3;
        for (size_t i = 0; i < nf; i++) {
            const int *q = F + i * 6;
            const float *p0 = V + q[0] * 3, *p1 = V + q[1] * 3, *p2 = V + q[2] * 3;
            float x0 = p0[ax], y0 = p0[ay], z0 = p0[az], x1 = p1[ax], y1 = p1[ay], z1 = p1[az], x2 = p2[ax], y2 = p2[ay], z2 = p2[az];
            float area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
            if (area == 0) continue;
            float inv = 1.0f / area;
            const float *u0 = T + q[3] * 2, *u1 = T + q[4] * 2, *u2 = T + q[5] * 2;
            int minx = (int)minf(x0, minf(x1, x2)), maxx = (int)maxf(x0, maxf(x1, x2));
            int miny = (int)minf(y0, minf(y1, y2)), maxy = (int)maxf(y0, maxf(y1, y2));
            for (int py = miny; py <= maxy; py++) {
                float fy = py + 0.5f;
                for (int px = minx; px <= maxx; px++) {
                    float fx = px + 0.5f;
                    float w0 = ((x1 - fx) * (y2 - fy) - (x2 - fx) * (y1 - fy)) * inv;
                    float w1 = ((x2 - fx) * (y0 - fy) - (x0 - fx) * (y2 - fy)) * inv;
                    float w2 = 1.0f - w0 - w1;
                    if (w0 < 0 || w1 < 0 || w2 < 0) continue;
                    float z = w0 * z0 + w1 * z1 + w2 * z2;
                    float u = w0 * u0[0] + w1 * u1[0] + w2 * u2[0], v = w0 * u0[1] + w1 * u1[1] + w2 * u2[1];
                    int tx = (int)(u * TW) & (TW - 1), ty = (int)(v * TW) & (TW - 1);
                    uint32_t c = tex[ty * TW + tx];
                    if ((c >> 24) < 128) continue;  // alpha test
                    int cc[3]; cc[az] = (int)z; cc[ax] = px; cc[ay] = py;   // back to one xyz layout
                    size_t idx = ((size_t)cc[2] * R + cc[1]) * R + cc[0];
                    vox[idx] = c;
                    frags++;
                }
            }
        }
    }
    double dt = now() - t0;
    size_t filled = 0; for (size_t i = 0; i < nvox; i++) filled += vox[i] != 0;
    printf("%s R=%d tris=%zu parse=%.2fs raster6=%.3fs frags=%ld (%.1f Mfrag/s, %.1f Mtri-setup/s) filled=%zu\n",
           argv[1], R, nf, tparse, dt, frags, frags / dt / 1e6, 6.0 * nf / dt / 1e6, filled);
    return 0;
}
