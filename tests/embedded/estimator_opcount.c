/* estimator_opcount.c - one predict and one update of a Kalman filter
 * (gen.EKF.to_c) between calls of kf_mark, for tests/features/
 * test_estimator_embedded.py, which runs it under qemu-arm with an
 * execution trace and counts the floating-point instructions executed
 * between the marks. The filter starts from its to_c values.
 *
 * Built with -DKF=<name> -DKF_HEADER='"<name>.h"'.
 */
#include KF_HEADER

#define KF_CAT2(a, b) a##b
#define KF_CAT(a, b) KF_CAT2(a, b)
#define KF_FN(suffix) KF_CAT(KF, suffix)

/* a call the trace can find (never inlined, no effect) */
__attribute__((noinline)) void kf_mark(int k);
__attribute__((noinline)) void kf_mark(int k)
{
    __asm__ volatile("" : : "r"(k) : "memory");
}

static KF_CAT(KF, _workspace) ws;
volatile gen_rt_real kf_in[8] = {0.01f, 0.02f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};

int main(void)
{
    gen_rt_real z[8], r[8];
    int i, st;
    st = KF_FN(_init)(&ws);
    if (!st) st = KF_FN(_defaults)(&ws);
    if (!st) st = KF_FN(_start)(&ws);
    for (i = 0; i < 8; ++i) z[i] = r[i] = kf_in[i];
    for (i = 0; i < 3 && !st; ++i) {   /* warm: two steps, then the measured one */
        kf_mark(0);
        if (!st) st = KF_FN(_predict)(&ws, r);
        kf_mark(1);
        if (!st) st = KF_FN(_update)(&ws, z);
        kf_mark(2);
    }
    return st ? 1 : 0;
}
