/* A program that uses liblanes as an outside project would: it includes only
 * <lanes/lanes.h>, builds an accel from its own arrays (a closed cube of 12
 * triangles and a tilted quad inside it), traces rays from the centre with
 * every query form, and checks each hit against its own brute force. Built
 * against the installed package by tests/check_consumer.cmake. */
#include <lanes/lanes.h>

#include <math.h>
#include <stdio.h>

static const float vertices[] = {
    -1, -1, -1, 1, -1, -1, 1, 1, -1, -1, 1, -1, /* cube corners 0-7 */
    -1, -1, 1,  1, -1, 1,  1, 1, 1,  -1, 1, 1,
    -0.5f, -0.5f, 0.2f, 0.5f, -0.5f, 0.4f, 0.5f, 0.5f, 0.4f, -0.5f, 0.5f, 0.2f, /* quad 8-11 */
};
static const uint32_t indices[] = {
    0, 1, 2, 0, 2, 3, 4, 6, 5, 4, 7, 6, 0, 4, 5, 0, 5, 1, /* -z, +z, -y */
    3, 2, 6, 3, 6, 7, 0, 3, 7, 0, 7, 4, 1, 5, 6, 1, 6, 2, /* +y, -x, +x */
    8, 9, 10, 8, 10, 11,                                  /* the quad */
};
enum { TRIANGLES = sizeof indices / sizeof indices[0] / 3, RAYS = 4096 };

/* Closest hit by brute force (Möller-Trumbore in double). */
static uint32_t brute_force(const float o[3], const float d[3], double *t_out)
{
    uint32_t best = LANES_INVALID_ID;
    double best_t = INFINITY;
    for (uint32_t i = 0; i < TRIANGLES; i++) {
        const float *p0 = vertices + 3 * indices[3 * i], *p1 = vertices + 3 * indices[3 * i + 1],
                    *p2 = vertices + 3 * indices[3 * i + 2];
        double e1[3], e2[3], s[3], p[3], q[3];
        for (int a = 0; a < 3; a++) e1[a] = p1[a] - p0[a], e2[a] = p2[a] - p0[a], s[a] = o[a] - p0[a];
        p[0] = d[1] * e2[2] - d[2] * e2[1], p[1] = d[2] * e2[0] - d[0] * e2[2], p[2] = d[0] * e2[1] - d[1] * e2[0];
        q[0] = s[1] * e1[2] - s[2] * e1[1], q[1] = s[2] * e1[0] - s[0] * e1[2], q[2] = s[0] * e1[1] - s[1] * e1[0];
        double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
        if (det == 0) continue;
        double u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) / det;
        double v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) / det;
        double t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
        if (u >= 0 && v >= 0 && u + v <= 1 && t >= 0 && t < best_t) best_t = t, best = i;
    }
    *t_out = best_t;
    return best;
}

int main(void)
{
    lanes_device device;
    lanes_accel accel;
    if (lanes_device_create("accuracy=robust", &device) != LANES_OK ||
        lanes_accel_create(device, vertices, 12, indices, TRIANGLES, &accel) != LANES_OK) {
        fprintf(stderr, "consumer: %s\n", lanes_last_error_message());
        return 1;
    }
    lanes_device_info info;
    lanes_device_get_info(device, &info);
    printf("consumer: liblanes %s (header %d.%d.%d), %s, %d lanes\n", lanes_version(),
           LANES_VERSION_MAJOR, LANES_VERSION_MINOR, LANES_VERSION_PATCH, info.isa, info.lanes);

    static float ox[RAYS], oy[RAYS], oz[RAYS], dx[RAYS], dy[RAYS], dz[RAYS], tn[RAYS], tf[RAYS];
    static float t[RAYS], u[RAYS], v[RAYS], tp[RAYS];
    static uint32_t prim[RAYS], primp[RAYS];
    static uint8_t occluded[RAYS];
    for (int i = 0; i < RAYS; i++) { /* directions spread over the sphere */
        double z = 1 - 2 * (i + 0.5) / RAYS, r = sqrt(1 - z * z), phi = i * 2.39996322972865332;
        ox[i] = 0.01f, oy[i] = -0.02f, oz[i] = 0.03f;
        dx[i] = (float)(r * cos(phi)), dy[i] = (float)(r * sin(phi)), dz[i] = (float)z;
        tn[i] = 0, tf[i] = INFINITY;
    }
    lanes_rays_soa rays = {ox, oy, oz, dx, dy, dz, tn, tf};
    lanes_hits_soa hits = {t, u, v, prim}, packet_hits = {tp, NULL, NULL, primp};
    if (lanes_intersect_stream(accel, &rays, RAYS, &hits) != LANES_OK ||
        lanes_intersect_packet(accel, &rays, RAYS, &packet_hits) != LANES_OK ||
        lanes_occluded_stream(accel, &rays, RAYS, occluded) != LANES_OK) {
        fprintf(stderr, "consumer: %s\n", lanes_last_error_message());
        return 1;
    }
    int passed = 0, failed = 0;
    for (int i = 0; i < RAYS; i++) {
        const float o[3] = {ox[i], oy[i], oz[i]}, d[3] = {dx[i], dy[i], dz[i]};
        double t_ref;
        uint32_t want = brute_force(o, d, &t_ref);
        lanes_ray1 ray = {{o[0], o[1], o[2]}, {d[0], d[1], d[2]}, 0.0f, INFINITY};
        lanes_hit1 one;
        lanes_intersect1(accel, &ray, &one);
        /* From inside a closed cube every ray hits; shared edges may go to
         * either triangle, at the same t. */
        int ok = prim[i] != LANES_INVALID_ID && fabs(t[i] - t_ref) <= 1e-5 * t_ref &&
                 (prim[i] == want || fabs(t[i] - t_ref) <= 1e-6) && one.prim_id == prim[i] &&
                 one.t == t[i] && tp[i] == t[i] && occluded[i] == 1;
        ok ? passed++ : failed++;
        if (!ok && failed <= 5)
            printf("ray %d: lanes prim %u t %.7g (single %u, packet %u), brute force prim %u t %.7g\n", i,
                   prim[i], t[i], one.prim_id, primp[i], want, t_ref);
    }
    lanes_accel_release(accel);
    lanes_device_release(device);
    printf("%d passed, %d failed\n", passed, failed);
    return failed ? 1 : 0;
}
