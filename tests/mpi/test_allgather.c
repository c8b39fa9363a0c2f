/*
 * test_allgather.c — the command's MPI all-gather (cli/cluster.c) under mpirun at any rank count: every
 * rank gets every rank's bytes, in rank order, whichever path it takes (Bruck et al.'s rounds over blocks
 * of any size, MPI_Allgatherv, or the large exchange's broadcasts), with unequal counts, zeros among them, every
 * rank's block empty, in place and from a separate buffer. Each byte is a function of its rank, its index
 * and the trial, so a block landing in another's place, shifted or cut short is caught. Built where MPI is
 * found; tests/mpi/test_allgather.sh runs it at 2 to 9 ranks.
 */
#include "../../cli/cluster.c"
#include "../../cli/message.c"

#include <stdint.h>

/* The same pseudo-random sequence on every rank, so that all hold the same counts. */
static uint32_t next(uint32_t *state)
{
    *state = *state * 1103515245u + 12345u;
    return *state >> 8;
}

static unsigned char byte_of(int rank, uint64_t i, int trial) { return (unsigned char)(rank * 31 + i * 7 + trial); }

int main(int argc, char **argv)
{
    int failed = 0;
    ic_comm *comm = ic_cli_cluster_start(&argc, &argv, &failed);
    if (!comm) {
        fprintf(stderr, "test_allgather: not started by mpirun\n");
        return 1;
    }
    mpi_comm *m = comm->user;
    const int n = comm->size, me = comm->rank;
    uint64_t *counts = malloc(sizeof *counts * (size_t)n);
    int bad = 0, small = 0, plain = 0;
    uint32_t state = 7;
    for (int trial = 0; trial < 400 && counts; ++trial) {
        /* Tiny blocks; a few kB with many zeros; blocks differing by one (a pass's records); up to 2 MB in
         * all, most very unequal (Bruck's rounds up to SMALL_LIMIT, MPI_Allgatherv above); all empty. */
        const int kind = trial % 5;
        uint64_t total = 0, at = 0;
        for (int r = 0; r < n; ++r) {
            uint32_t x = next(&state);
            counts[r] = kind == 0   ? x % 7
                        : kind == 1 ? (x % 3 == 0 ? 0 : x % 5000)
                        : kind == 2 ? 400000 / (uint64_t)n + x % 2
                        : kind == 3 ? x % 2000000 / (uint64_t)n * (uint64_t)(r % 3)
                                    : 0;
            total += counts[r];
            at += r < me ? counts[r] : 0;
        }
        unsigned char *recv = calloc(total + 1, 1), *send = malloc(counts[me] + 1);
        if (!recv || !send) {
            fprintf(stderr, "test_allgather: out of memory\n");
            MPI_Abort(MPI_COMM_WORLD, 1);
        }
        for (uint64_t i = 0; i < counts[me]; ++i)
            send[i] = byte_of(me, i, trial);
        const int in_place = trial & 1;
        if (in_place)
            memcpy(recv + at, send, counts[me]);
        const int bruck = total <= SMALL_LIMIT;
        small += n > 2 && bruck;
        plain += n > 2 && !bruck;
        if (mpi_allgather(m, in_place ? recv + at : send, recv, counts) != IC_OK)
            ++bad;
        uint64_t o = 0;
        for (int r = 0; r < n; ++r)
            for (uint64_t i = 0; i < counts[r]; ++i, ++o)
                if (recv[o] != byte_of(r, i, trial)) {
                    if (!bad++)
                        fprintf(stderr, "test_allgather: %d ranks, trial %d: rank %d's byte %llu of rank %d's "
                                "block is wrong\n", n, trial, me, (unsigned long long)i, r);
                    r = n;
                    break;
                }
        free(recv);
        free(send);
    }
    /* Both paths were taken (at 3 ranks and more), or the test tested less than it says. */
    if (n > 2 && (small == 0 || plain == 0)) {
        fprintf(stderr, "test_allgather: %d ranks: %d Bruck and %d MPI_Allgatherv all-gathers; expected both\n", n, small,
                plain);
        ++bad;
    }
    int all_bad = 0;
    MPI_Allreduce(&bad, &all_bad, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
    if (me == 0)
        printf("%d ranks: %s\n", n, all_bad ? "FAILED" : "every rank holds every block");
    free(counts);
    ic_cli_cluster_end(comm);
    return all_bad != 0;
}
