/*
 * cluster.c — the command's processes (cluster.h): the one file that calls MPI. Built with MPI when the
 * build found it (IRRCACHE_MPI); without it every function is the one-process case.
 *
 * Only the main thread calls MPI (MPI_THREAD_FUNNELED): the library calls its comm from the thread
 * that called ic_render, never from its worker threads.
 */
#include "cluster.h"
#include "cli.h"

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#ifdef IRRCACHE_MPI
#include <mpi.h>

typedef struct mpi_comm {
    ic_comm comm;
    int *counts, *displs;   /* per rank, for MPI_Allgatherv and the receiving side of MPI_Alltoallv */
    int *scounts, *sdispls; /* per rank, the sending side of MPI_Alltoallv */
    uint64_t allgather_limit; /* bytes above which an all-gather takes allgather_large: INT32_MAX, or less
                                 from IRRCACHE_MPI_ALLGATHER_LIMIT, which tests/mpi sets to run that path
                                 on small images */
    int chunk;                /* bytes per call on that path */
    unsigned char *scratch;   /* allgather_small's blocks in its order (SMALL_LIMIT bytes) */
    FILE *trace;              /* IRRCACHE_MPI_TRACE: rank 0's exchanges, one line each, or NULL */
} mpi_comm;

/* A line of IRRCACHE_MPI_TRACE: the operation, the bytes rank 0 received in it and the rounds of messages it
 * took one after another (what a link's latency multiplies; 0 for a message, which overlaps the work). */
static void trace(const mpi_comm *m, const char *op, uint64_t bytes, int rounds)
{
    if (m->trace)
        fprintf(m->trace, "%s %llu %d\n", op, (unsigned long long)bytes, rounds);
}

/* Rounds of Bruck's all-gather among n ranks: ceil(log2 n). */
static int log2_rounds(int n)
{
    int k = 0;
    while ((1 << k) < n)
        ++k;
    return k;
}

/* counts (bytes per rank) as MPI's int counts and displacements; 0 if a count or the total exceeds limit
 * (at most INT32_MAX). */
static int int_counts(const uint64_t *bytes, int size, int *counts, int *displs, uint64_t limit)
{
    uint64_t total = 0;
    for (int r = 0; r < size; ++r) {
        if (bytes[r] > limit || total > limit)
            return 0;
        counts[r] = (int)bytes[r];
        displs[r] = (int)total;
        total += bytes[r];
    }
    return 1;
}

/* An all-gather too large for int counts and displacements (above 2 GiB in all: a huge image's pixels):
 * each rank's block broadcast from it, in chunks. Slower than MPI_Allgatherv, but only such exchanges
 * take it. */
static ic_result allgather_large(const mpi_comm *m, const void *send, void *recv, const uint64_t *counts)
{
    uint64_t at = 0;
    for (int r = 0; r < m->comm.size; ++r) {
        char *block = (char *)recv + at;
        if (r == m->comm.rank && send != block)
            memmove(block, send, counts[r]);
        for (uint64_t done = 0; done < counts[r];) {
            int n = counts[r] - done > (uint64_t)m->chunk ? m->chunk : (int)(counts[r] - done);
            if (MPI_Bcast(block + done, n, MPI_BYTE, r, MPI_COMM_WORLD) != MPI_SUCCESS)
                return IC_ERR_IO;
            done += (uint64_t)n;
        }
        at += counts[r];
    }
    return IC_OK;
}

/* Bytes in all up to which an all-gather takes allgather_small. */
#define SMALL_LIMIT (1 << 20)

/* An all-gather of at most SMALL_LIMIT bytes in all (counts, candidates' tallies, a pass's records) in
 * ceil(log2 N) rounds of messages, whichever algorithm the MPI library would choose for MPI_Allgatherv (a
 * ring takes N − 1): Bruck et al.'s concatenation (IEEE TPDS 1997), with blocks of any size. A rank keeps
 * the blocks of ranks rank, rank + 1, … (mod N) one after another; in each round, holding `have` of them,
 * it sends the first min(have, N − have) to rank − have and receives as many from rank + have, whose first
 * blocks are the ones it lacks next. Every rank knows every count, so each round's sizes are known to
 * both sides, and a rank receives the same bytes as in a ring. On a slow link a round costs the link's
 * latency: at 16 ranks an exchange takes 4 rounds instead of 15. */
static ic_result allgather_small(mpi_comm *m, const void *send, void *recv, const uint64_t *counts)
{
    const int n = m->comm.size, rank = m->comm.rank;
    unsigned char *held = m->scratch; /* the blocks of ranks rank, rank + 1, … (mod n), in that order */
    memcpy(held, send, counts[rank]);
    uint64_t held_bytes = counts[rank];
    for (int have = 1; have < n;) {
        int take = have < n - have ? have : n - have;
        uint64_t out = 0, in = 0;
        for (int j = 0; j < take; ++j) {
            out += counts[(rank + j) % n];
            in += counts[(rank + have + j) % n];
        }
        if (MPI_Sendrecv(held, (int)out, MPI_BYTE, (rank - have + n) % n, 0, held + held_bytes, (int)in, MPI_BYTE,
                         (rank + have) % n, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE) != MPI_SUCCESS)
            return IC_ERR_IO;
        held_bytes += in;
        have += take;
    }
    for (int j = 0, at = 0; j < n; at += (int)counts[(rank + j) % n], ++j) {
        int q = (rank + j) % n;
        memmove((char *)recv + m->displs[q], held + at, counts[q]);
    }
    return IC_OK;
}

/* MPI counts and displacements are int: an exchange above 2 GiB in all takes allgather_large. Every rank
 * holds the same counts, so all take the same path. */
static ic_result mpi_allgather(void *user, const void *send, void *recv, const uint64_t *counts)
{
    mpi_comm *m = user;
    uint64_t total = 0;
    for (int r = 0; r < m->comm.size; ++r)
        total += counts[r];
    if (!int_counts(counts, m->comm.size, m->counts, m->displs, m->allgather_limit)) {
        trace(m, "allgather-large", total - counts[m->comm.rank], m->comm.size - 1);
        return allgather_large(m, send, recv, counts);
    }
    if (m->comm.size > 2 && total <= SMALL_LIMIT) {
        trace(m, "allgather-small", total - counts[m->comm.rank], log2_rounds(m->comm.size));
        return allgather_small(m, send, recv, counts);
    }
    trace(m, "allgather", total - counts[m->comm.rank], m->comm.size - 1);
    const void *s = send == (const char *)recv + m->displs[m->comm.rank] ? MPI_IN_PLACE : send;
    int rc = MPI_Allgatherv(s, m->counts[m->comm.rank], MPI_BYTE, recv, m->counts, m->displs, MPI_BYTE,
                            MPI_COMM_WORLD);
    return rc == MPI_SUCCESS ? IC_OK : IC_ERR_IO;
}

/* Above 2 GiB to or from one rank, refused (IC_ERR_UNSUPPORTED): the library's all-to-alls move a band
 * of rows or a range of candidates, far below that; a rank's counts are its own, so a large-exchange
 * path would first need the ranks to agree on taking it, a collective every all-to-all would pay. */
static ic_result mpi_alltoall(void *user, const void *send, const uint64_t *send_counts, void *recv,
                              const uint64_t *recv_counts)
{
    mpi_comm *m = user;
    if (!int_counts(send_counts, m->comm.size, m->scounts, m->sdispls, INT32_MAX) ||
        !int_counts(recv_counts, m->comm.size, m->counts, m->displs, INT32_MAX))
        return IC_ERR_UNSUPPORTED;
    uint64_t total = 0;
    for (int r = 0; r < m->comm.size; ++r)
        total += r == m->comm.rank ? 0 : recv_counts[r];
    trace(m, "alltoall", total, m->comm.size - 1);
    int rc = MPI_Alltoallv(send, m->scounts, m->sdispls, MPI_BYTE, recv, m->counts, m->displs, MPI_BYTE,
                           MPI_COMM_WORLD);
    return rc == MPI_SUCCESS ? IC_OK : IC_ERR_IO;
}

/* The library's messages between two ranks (irrcache/comm.h): tag MESSAGE_TAG, apart from
 * allgather_small's tag 0 (and from the collectives, which MPI keeps apart from every message). */
#define MESSAGE_TAG 1

static ic_result mpi_post(void *user, int to, const void *buf, uint64_t bytes, void **request)
{
    (void)user;
    MPI_Request *req = malloc(sizeof *req);
    if (!req)
        return IC_ERR_OOM;
    if (bytes > INT32_MAX) {
        free(req);
        return IC_ERR_UNSUPPORTED;
    }
    if (MPI_Isend(buf, (int)bytes, MPI_BYTE, to, MESSAGE_TAG, MPI_COMM_WORLD, req) != MPI_SUCCESS) {
        free(req);
        return IC_ERR_IO;
    }
    *request = req;
    return IC_OK;
}

static ic_result mpi_sent(void *user, void *request, int wait, int *done)
{
    (void)user;
    MPI_Request *req = request;
    int rc = wait ? MPI_Wait(req, MPI_STATUS_IGNORE) : MPI_Test(req, done, MPI_STATUS_IGNORE);
    if (wait)
        *done = 1;
    if (rc != MPI_SUCCESS)
        return IC_ERR_IO;
    if (*done)
        free(req);
    return IC_OK;
}

static ic_result mpi_take(void *user, void *buf, uint64_t room, int wait, int *from, uint64_t *bytes)
{
    const mpi_comm *m = user;
    MPI_Status st;
    int arrived = 1, n = 0;
    int rc = wait ? MPI_Probe(MPI_ANY_SOURCE, MESSAGE_TAG, MPI_COMM_WORLD, &st)
                  : MPI_Iprobe(MPI_ANY_SOURCE, MESSAGE_TAG, MPI_COMM_WORLD, &arrived, &st);
    *bytes = 0;
    if (rc != MPI_SUCCESS)
        return IC_ERR_IO;
    if (!arrived)
        return IC_OK;
    MPI_Get_count(&st, MPI_BYTE, &n);
    if (n < 0 || (uint64_t)n > room)
        return IC_ERR_IO;
    if (MPI_Recv(buf, n, MPI_BYTE, st.MPI_SOURCE, MESSAGE_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE) != MPI_SUCCESS)
        return IC_ERR_IO;
    *from = st.MPI_SOURCE;
    *bytes = (uint64_t)n;
    trace(m, "message", (uint64_t)n, 0);
    return IC_OK;
}

static ic_result mpi_sum(void *user, double *values, uint64_t count)
{
    const mpi_comm *m = user;
    trace(m, "sum", count * sizeof *values * (uint64_t)log2_rounds(m->comm.size), log2_rounds(m->comm.size));
    /* In chunks that fit an int count. */
    for (uint64_t done = 0; done < count;) {
        int n = count - done > (uint64_t)(1 << 28) ? 1 << 28 : (int)(count - done);
        if (MPI_Allreduce(MPI_IN_PLACE, values + done, n, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD) != MPI_SUCCESS)
            return IC_ERR_IO;
        done += (uint64_t)n;
    }
    return IC_OK;
}

static ic_result mpi_broadcast(void *user, void *buf, uint64_t bytes, int root)
{
    const mpi_comm *m = user;
    trace(m, "broadcast", m->comm.rank == root ? 0 : bytes, log2_rounds(m->comm.size));
    for (uint64_t done = 0; done < bytes;) {
        int n = bytes - done > (uint64_t)(1 << 30) ? 1 << 30 : (int)(bytes - done);
        if (MPI_Bcast((char *)buf + done, n, MPI_BYTE, root, MPI_COMM_WORLD) != MPI_SUCCESS)
            return IC_ERR_IO;
        done += (uint64_t)n;
    }
    return IC_OK;
}

/* Started by an MPI launcher: Open MPI's mpirun and PMIx- or PMI-based launchers (srun) say so in the
 * environment. Without one the program stays a plain process: MPI_Init alone would start a singleton
 * job, slower to start and needing the launcher's daemon. */
static int under_launcher(void)
{
    static const char *vars[] = {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"};
    for (size_t i = 0; i < sizeof vars / sizeof vars[0]; ++i)
        if (getenv(vars[i]))
            return 1;
    return 0;
}

ic_comm *ic_cli_cluster_start(int *argc, char ***argv, int *failed)
{
    *failed = 0;
    if (!under_launcher())
        return NULL;
    int provided = 0;
    if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) {
        ic_cli_eprintf("irrcache: MPI could not start; check the launcher (mpirun) and its hostfile\n");
        *failed = 1;
        return NULL;
    }
    if (provided < MPI_THREAD_FUNNELED) {
        ic_cli_eprintf("irrcache: this MPI library cannot be called from one thread of a threaded program "
                        "(MPI_THREAD_FUNNELED); use an MPI built with thread support, or run the plain build\n");
        MPI_Abort(MPI_COMM_WORLD, 1);
        return NULL;
    }
    mpi_comm *m = calloc(1, sizeof *m);
    int size = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    if (m) {
        m->counts = calloc((size_t)size, sizeof *m->counts);
        m->displs = calloc((size_t)size, sizeof *m->displs);
        m->scounts = calloc((size_t)size, sizeof *m->scounts);
        m->sdispls = calloc((size_t)size, sizeof *m->sdispls);
        m->scratch = malloc(SMALL_LIMIT);
    }
    if (!m || !m->counts || !m->displs || !m->scounts || !m->sdispls || !m->scratch) {
        ic_cli_eprintf("irrcache: out of memory starting %d MPI ranks\n", size);
        MPI_Abort(MPI_COMM_WORLD, 1);
        return NULL;
    }
    m->comm.size = size;
    MPI_Comm_rank(MPI_COMM_WORLD, &m->comm.rank);
    m->comm.user = m;
    m->allgather_limit = INT32_MAX;
    m->chunk = 1 << 30;
    const char *limit = getenv("IRRCACHE_MPI_ALLGATHER_LIMIT");
    if (limit && atoll(limit) > 0 && atoll(limit) < INT32_MAX) {
        m->allgather_limit = (uint64_t)atoll(limit);
        m->chunk = (int)(m->allgather_limit / 2 + 1);
    }
    const char *trace_path = getenv("IRRCACHE_MPI_TRACE");
    if (trace_path && *trace_path && m->comm.rank == 0 && !(m->trace = fopen(trace_path, "w")))
        ic_cli_eprintf("irrcache: cannot write IRRCACHE_MPI_TRACE file %s; going on without it\n", trace_path);
    m->comm.allgather = mpi_allgather;
    m->comm.sum = mpi_sum;
    m->comm.broadcast = mpi_broadcast;
    m->comm.alltoall = mpi_alltoall;
    m->comm.post = mpi_post;
    m->comm.sent = mpi_sent;
    m->comm.take = mpi_take;
    return &m->comm;
}

void ic_cli_cluster_end(ic_comm *comm)
{
    if (!comm)
        return;
    mpi_comm *m = comm->user;
    if (m->trace)
        fclose(m->trace);
    MPI_Finalize();
    free(m->scratch);
    free(m->counts);
    free(m->displs);
    free(m->scounts);
    free(m->sdispls);
    free(m);
}

int ic_cli_cluster_first_failure(ic_comm *comm, int failed)
{
    if (!comm)
        return failed ? 0 : -1;
    int mine = failed ? comm->rank : comm->size, first = comm->size;
    if (MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD) != MPI_SUCCESS)
        MPI_Abort(MPI_COMM_WORLD, 1);
    return first < comm->size ? first : -1;
}

void ic_cli_cluster_abort(ic_comm *comm, int code)
{
    if (comm && comm->size > 1) {
        fflush(stderr);
        MPI_Abort(MPI_COMM_WORLD, code);
    }
}

void ic_cli_cluster_broadcast(ic_comm *comm, void *buf, uint64_t bytes)
{
    if (comm && comm->size > 1 && mpi_broadcast(comm->user, buf, bytes, 0) != IC_OK)
        MPI_Abort(MPI_COMM_WORLD, 1);
}

void ic_cli_cluster_gather(ic_comm *comm, const double *mine, int count, double *all)
{
    if (!comm) {
        memcpy(all, mine, sizeof *mine * (size_t)count);
        return;
    }
    MPI_Gather(mine, count, MPI_DOUBLE, all, count, MPI_DOUBLE, 0, MPI_COMM_WORLD);
}

#else /* one process */

ic_comm *ic_cli_cluster_start(int *argc, char ***argv, int *failed)
{
    (void)argc;
    (void)argv;
    *failed = 0;
    return NULL;
}
void ic_cli_cluster_end(ic_comm *comm) { (void)comm; }
int ic_cli_cluster_first_failure(ic_comm *comm, int failed)
{
    (void)comm;
    return failed ? 0 : -1;
}
void ic_cli_cluster_abort(ic_comm *comm, int code)
{
    (void)comm;
    (void)code;
}
void ic_cli_cluster_broadcast(ic_comm *comm, void *buf, uint64_t bytes)
{
    (void)comm;
    (void)buf;
    (void)bytes;
}
void ic_cli_cluster_gather(ic_comm *comm, const double *mine, int count, double *all)
{
    (void)comm;
    memcpy(all, mine, sizeof *mine * (size_t)count);
}
#endif

int ic_cli_cluster_rank(const ic_comm *comm) { return comm ? comm->rank : 0; }

int ic_cli_cluster_mute(int mute)
{
    if (!mute)
        return -1;
    fflush(stderr);
    int saved = dup(2), null_fd = open("/dev/null", O_WRONLY);
    if (saved >= 0 && null_fd >= 0)
        dup2(null_fd, 2);
    if (null_fd >= 0)
        close(null_fd);
    if (saved >= 0 && null_fd < 0) {
        close(saved);
        return -1;
    }
    return saved;
}

void ic_cli_cluster_unmute(int saved)
{
    if (saved < 0)
        return;
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
}
int ic_cli_cluster_size(const ic_comm *comm) { return comm ? comm->size : 1; }

int ic_cli_cluster_agree(ic_comm *comm, int status, const char *message, const char *command)
{
    int first = ic_cli_cluster_first_failure(comm, status != 0);
    if (first < 0)
        return 0;
    if (first == ic_cli_cluster_rank(comm) && message[0])
        ic_cli_eprintf("%s\n", message);
    else if (command && first == ic_cli_cluster_rank(comm) && first != 0)
        ic_cli_eprintf("%s: rank %d of %d: its command line is invalid; run it alone to see why\n", command, first,
                ic_cli_cluster_size(comm));
    return status ? status : 1;
}
