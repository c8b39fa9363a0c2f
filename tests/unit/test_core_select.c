/*
 * test_core_select.c — core/select.h against brute force: the k-th smallest against a sorted copy for every
 * k of arrays with many ties, signed zeros and sorted or reversed runs; the radix sort of keyed indices
 * against a comparison sort by (key, position), which is what stability means.
 */
#include "core/select.h"

#include "test_util.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static uint32_t next(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return *s >> 8;
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

static void test_kth_smallest(void)
{
    uint32_t s = 12345;
    for (size_t n = 1; n <= 300; n += (n < 20 ? 1 : 37)) {
        for (int kind = 0; kind < 5; ++kind) {
            float *v = malloc(sizeof *v * n), *sorted = malloc(sizeof *sorted * n), *work = malloc(sizeof *work * n);
            for (size_t i = 0; i < n; ++i) {
                switch (kind) {
                case 0: v[i] = (float)(next(&s) % 1000) / 7.0f - 50.0f; break; /* spread */
                case 1: v[i] = (float)(next(&s) % 3); break;                   /* few values, many ties */
                case 2: v[i] = (float)i; break;                                /* sorted */
                case 3: v[i] = (float)(n - i); break;                          /* reversed */
                default: v[i] = next(&s) % 2 ? 0.0f : -0.0f; break;            /* zeros of both signs */
                }
            }
            memcpy(sorted, v, sizeof *v * n);
            qsort(sorted, n, sizeof *sorted, cmp_float);
            size_t bad = 0;
            for (size_t k = 0; k < n; ++k) {
                memcpy(work, v, sizeof *v * n);
                bad += ic_kth_smallest(work, n, k) != sorted[k];
            }
            CHECK(bad == 0, "k-th smallest of %zu values (kind %d): %zu of the k differ from a sort", n, kind, bad);
            free(v);
            free(sorted);
            free(work);
        }
    }
}

/* An organ pipe (0, 1, …, n/2 − 1, then down again) makes the middle element the largest of its range round
 * after round: with the middle as the pivot alone each round took off two values, about 2 minutes for one
 * selection of 2^20 values (2.5 s for the view extent's 57,600 points). alarm: a hang fails the test. */
static void test_kth_smallest_organ_pipe(void)
{
    const size_t n = (size_t)1 << 20;
    float *v = malloc(sizeof *v * n), *sorted = malloc(sizeof *sorted * n), *work = malloc(sizeof *work * n);
    for (size_t i = 0; i < n; ++i)
        v[i] = (float)(i < n / 2 ? i : n - 1 - i);
    memcpy(sorted, v, sizeof *v * n);
    qsort(sorted, n, sizeof *sorted, cmp_float);
    alarm(60);
    const size_t ks[] = {0, n / 20, n / 2, n * 19 / 20, n - 1};
    for (size_t q = 0; q < sizeof ks / sizeof ks[0]; ++q) {
        memcpy(work, v, sizeof *v * n);
        float got = ic_kth_smallest(work, n, ks[q]);
        CHECK(got == sorted[ks[q]], "organ pipe of %zu values: k = %zu gives %g, a sort %g", n, ks[q], (double)got,
              (double)sorted[ks[q]]);
    }
    alarm(0);
    free(v);
    free(sorted);
    free(work);
}

typedef struct with_position {
    ic_key_index e;
    size_t position;
} with_position;

static int cmp_key_position(const void *a, const void *b)
{
    const with_position *x = a, *y = b;
    if (x->e.key != y->e.key)
        return x->e.key < y->e.key ? -1 : 1;
    return (x->position > y->position) - (x->position < y->position);
}

static void test_sort_key_index(void)
{
    uint32_t s = 777;
    static const uint32_t masks[] = {0xffffffffu, 0x3fffffffu, 0xff00u, 0x7u, 0u};
    for (size_t m = 0; m < sizeof masks / sizeof masks[0]; ++m) {
        for (size_t n = 0; n <= 5000; n = n ? n * 3 + 1 : 1) {
            ic_key_index *a = malloc(sizeof *a * (n + 1)), *tmp = malloc(sizeof *tmp * (n + 1));
            with_position *ref = malloc(sizeof *ref * (n + 1));
            for (size_t i = 0; i < n; ++i) {
                a[i] = (ic_key_index){(next(&s) << 8 ^ next(&s)) & masks[m], next(&s)};
                ref[i] = (with_position){a[i], i};
            }
            qsort(ref, n, sizeof *ref, cmp_key_position);
            const ic_key_index *got = ic_sort_key_index(a, tmp, n);
            size_t bad = 0;
            for (size_t i = 0; i < n; ++i)
                bad += got[i].key != ref[i].e.key || got[i].index != ref[i].e.index;
            CHECK(bad == 0, "radix sort of %zu keys (mask %#x): %zu places differ from a stable sort", n, masks[m], bad);
            free(a);
            free(tmp);
            free(ref);
        }
    }
}

int main(void)
{
    test_kth_smallest();
    test_kth_smallest_organ_pipe();
    test_sort_key_index();
    TEST_MAIN_END();
}
