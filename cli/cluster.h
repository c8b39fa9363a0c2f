/*
 * cluster.h — the command's processes: under mpirun (an MPI build, IRRCACHE_MPI) a render is shared by
 * every rank, each calling the library with an ic_comm over MPI (irrcache/comm.h); otherwise, and in a
 * build without MPI, one process, comm NULL.
 *
 * Failures: a failure every rank meets alike before the render (options, the scene) is agreed on
 * (ic_cli_cluster_first_failure), so one rank prints it and every rank exits non-zero; a failure during
 * the render, when the other ranks wait in a collective operation, ends the whole job
 * (ic_cli_cluster_abort) after the failing rank printed its message.
 */
#ifndef IC_CLI_CLUSTER_H
#define IC_CLI_CLUSTER_H

#include "irrcache/comm.h"

#include <stdint.h>

/* Joins the job if the program was started by an MPI launcher (else one process); returns the comm to
 * give the library (NULL for one process) or NULL with *failed set and a message printed. */
ic_comm *ic_cli_cluster_start(int *argc, char ***argv, int *failed);
/* Leaves the job (MPI_Finalize); NULL-safe. */
void ic_cli_cluster_end(ic_comm *comm);
/* This rank and the number of ranks (0 and 1 without a job). */
int ic_cli_cluster_rank(const ic_comm *comm);
int ic_cli_cluster_size(const ic_comm *comm);
/* Collective: the lowest rank whose `failed` is non-zero, or −1 when none failed. */
int ic_cli_cluster_first_failure(ic_comm *comm, int failed);
/* Collective, before the work: what failed on this rank (status, and its message not yet printed, may be
 * empty) agreed on by every rank. The lowest failing rank prints its message, or, with `command` non-NULL
 * and no message on a rank other than 0, a line saying its command line is invalid. Returns the status
 * this rank exits with (1 when another rank failed), 0 when every rank may go on. */
int ic_cli_cluster_agree(ic_comm *comm, int status, const char *message, const char *command);
/* Ends every rank of the job with exit status `code` (one process: returns). */
void ic_cli_cluster_abort(ic_comm *comm, int code);
/* Collective: rank 0's bytes at buf copied to every rank. */
void ic_cli_cluster_broadcast(ic_comm *comm, void *buf, uint64_t bytes);
/* Silences this process's standard error (mute non-zero) until ic_cli_cluster_unmute(the returned
 * value): ranks other than 0 parse the same command line as rank 0, which alone reports its errors. */
int ic_cli_cluster_mute(int mute);
void ic_cli_cluster_unmute(int saved);
/* Collective: every rank's `count` values of `mine` into all (room for size × count, rank 0 only). */
void ic_cli_cluster_gather(ic_comm *comm, const double *mine, int count, double *all);

#endif
