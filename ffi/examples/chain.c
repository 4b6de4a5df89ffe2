/* Steps the paper's Figure 1 (c) chain (25 beads, f32, Overdamped, 200 steps)
 * through the C interface, with the scene's soft contact as a force callback, and
 * prints a digest of the positions' bits; then the same chain at kT = 0.5 (a
 * Brownian run from a seeded generator, saved and restored halfway by copying it),
 * with its own digest line. The line is the same on x86_64 and on a
 * Cortex-M4 under QEMU, and its digest equals the Rust firmware's. Build: see
 * docs/FIRMWARE.md ("Calling from C"); compile with -ffp-contract=off so that no
 * multiply-add is fused (that would change the bits). */
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "hydrorattle.h"

enum { N = 25, B = 24, STEPS = 200 };

static float pos[N][3], vel[N][3], omega[N][3], radius[N], density[N];
static HrBondF32 bonds[B];
/* Scratch for the kernel; main checks it against hr_storage_bytes_f32. */
static uint64_t storage[64 * 1024 / sizeof(uint64_t)];

/* Overlapping spheres repel with stiffness * overlap, along their line of centres. */
static void contact(void *user, size_t n, const float (*p)[3], const float *a,
                    float (*f)[3]) {
    const float k = *(const float *)user;
    for (size_t i = 0; i < n; i++) {
        for (size_t j = 0; j < i; j++) {
            float r[3] = {p[i][0] - p[j][0], p[i][1] - p[j][1], p[i][2] - p[j][2]};
            float reach = a[i] + a[j];
            float s2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
            if (s2 < reach * reach && s2 > 0.0f) {
                float s = sqrtf(s2);
                float c = k * (reach - s) / s;
                for (int d = 0; d < 3; d++) {
                    f[i][d] += r[d] * c;
                    f[j][d] -= r[d] * c;
                }
            }
        }
    }
}

/* FNV-1a over the little-endian bytes of every position component's bits. */
static uint64_t digest(void) {
    uint64_t h = 0xcbf29ce484222325u;
    for (int i = 0; i < N; i++) {
        for (int d = 0; d < 3; d++) {
            uint32_t bits;
            memcpy(&bits, &pos[i][d], sizeof bits);
            for (int b = 0; b < 4; b++) {
                h = (h ^ ((bits >> (8 * b)) & 0xffu)) * 0x100000001b3u;
            }
        }
    }
    return h;
}

/* The chain again at kT = 0.5 (midpoint drift, seed 7). The generator is plain data:
 * a copy taken with the state after STEPS / 2 steps and put back reruns the second
 * half to the same bits (checked). */
static int brownian(float *stiffness) {
    if (hr_figure1c_f32(pos, radius, density, bonds) != HR_STATUS_OK) {
        return 1;
    }
    memset(vel, 0, sizeof vel);
    memset(omega, 0, sizeof omega);
    HrParamsF32 params = hr_params_default_f32(0.005f);
    params.solver = HR_SOLVER_NEWTON;
    params.max_iterations = 500;
    params.allow_overlap = 1;
    params.temperature = 0.5f;
    params.drift = HR_DRIFT_MIDPOINT;
    size_t need = hr_storage_bytes_f32(&params, N, B);
    if (need == 0 || need > sizeof storage) {
        printf("storage: need %u bytes, have %u\n", (unsigned)need, (unsigned)sizeof storage);
        return 1;
    }
    HrNoise noise = hr_noise_seed(7), saved_noise;
    HrStateF32 state = {N, pos, vel, omega, radius, density, 0.0f, &noise};
    static float saved_pos[N][3];
    float saved_time = 0.0f;
    uint64_t first = 0;
    for (int pass = 0; pass < 2; pass++) {
        for (int s = pass ? STEPS / 2 : 0; s < STEPS; s++) {
            if (s == STEPS / 2 && pass == 0) {
                memcpy(saved_pos, pos, sizeof pos);
                saved_noise = noise;
                saved_time = state.time;
            }
            HrStatus st = hr_step_f32(&state, bonds, B, &params, storage, sizeof storage,
                                      contact, stiffness, NULL);
            if (st != HR_STATUS_OK) {
                printf("brownian step %d failed (%d): %s\n", s, (int)st, hr_error_message(st));
                return 1;
            }
        }
        if (pass == 0) {
            first = digest();
            memcpy(pos, saved_pos, sizeof pos);
            noise = saved_noise;
            state.time = saved_time;
        }
    }
    if (digest() != first) {
        printf("restored generator: digest %016llx, not %016llx\n",
               (unsigned long long)digest(), (unsigned long long)first);
        return 1;
    }
    printf("c figure1c f32 Overdamped kT=0.5 seed=7 steps=%d digest=%016llx (restart from step %d: same)\n",
           STEPS, (unsigned long long)first, STEPS / 2);
    return 0;
}

int main(void) {
    if (hr_figure1c_f32(pos, radius, density, bonds) != HR_STATUS_OK) {
        return 1;
    }
    HrParamsF32 params = hr_params_default_f32(0.005f);
    params.method = HR_METHOD_OVERDAMPED;
    params.solver = HR_SOLVER_NEWTON;
    params.max_iterations = 500;
    params.allow_overlap = 1;
    size_t need = hr_storage_bytes_f32(&params, N, B);
    if (need == 0 || need > sizeof storage) {
        printf("storage: need %u bytes, have %u\n", (unsigned)need, (unsigned)sizeof storage);
        return 1;
    }
    HrStateF32 state = {N, pos, vel, omega, radius, density, 0.0f, NULL};
    HrReportF32 report;
    float stiffness = 1000.0f;
    for (int s = 0; s < STEPS; s++) {
        HrStatus st = hr_step_f32(&state, bonds, B, &params, storage, sizeof storage,
                                  contact, &stiffness, &report);
        if (st != HR_STATUS_OK) {
            printf("step %d failed (%d): %s\n", s, (int)st, hr_error_message(st));
            return 1;
        }
    }
    uint32_t residual;
    memcpy(&residual, &report.residual, sizeof residual);
    printf("c figure1c f32 Overdamped steps=%d digest=%016llx iterations=%lu "
           "residual=0x%08lx\n",
           STEPS, (unsigned long long)digest(), (unsigned long)report.iterations,
           (unsigned long)residual);
    return brownian(&stiffness);
}
