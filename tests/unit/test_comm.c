/*
 * test_comm.c — a render shared by several processes (irrcache/comm.h) gives the bits one process gives, and
 * counts the rays one process counts.
 * The "processes" are threads of this program, each calling ic_render with its own ic_comm over an
 * in-memory transport (a barrier and shared pointers), so the library's side runs in every build,
 * the sanitizer build included, with no MPI: the cache (batch and adaptive; elliptical Hessian records),
 * the path tracer, a loaded cache file and the sensor points at 2, 3 and 5 ranks against one process with
 * 2 threads; under a time budget (path tracer and cache) every rank the same image; cache insertions shared
 * by 3 ranks (ic_cache_set_comm) the records one process makes; the world stage's clustering over 2–5
 * ranks the selection of one process. tests/mpi/test_mpi.sh does the same through
 * mpirun.
 */
#include "test_util.h"

#include "test_render_util.h"

#include "core/rng.h"
#include "integrators/ic_world.h"
#include "irrcache/cache.h"
#include "irrcache/points.h"

#include <pthread.h>
#include <string.h>
#include <time.h>

#define SCENE IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json"
#define CACHE_FILE IC_TEST_TMP "/test_comm.cache"
#define MAX_RANKS 5
#define SIZE 32

/* ---- the in-memory transport: every rank publishes what it has, waits for all, reads the others' */
typedef struct message {
    struct message *next;
    int from;
    uint64_t bytes;
    unsigned char data[];
} message;

typedef struct transport {
    int size;
    pthread_barrier_t barrier;
    const void *published[MAX_RANKS];
    /* Messages (post, sent, take): each rank's mailbox, in the order they arrived. */
    pthread_mutex_t lock;
    pthread_cond_t arrived;
    message *first[MAX_RANKS], *last[MAX_RANKS];
    int messages;
    /* A slow link (slow_seconds > 0): the messages from rank slow_from to rank slow_to arrive after the
     * others (fake_take). */
    int slow_from, slow_to;
    double slow_seconds;
} transport;

typedef struct rank_link {
    transport *t;
    int rank;
    int sums;           /* sums this rank took part in */
    int fail_sum_from;  /* > 0: that sum and every later one fail on this rank, after the exchange */
    int allgathers;     /* all-gathers this rank took part in */
    int damage_allgather; /* > 0: that all-gather delivers the next rank's block damaged (damage_block) */
} rank_link;

/* A block as a faulty transport might deliver it: its first ten bytes replaced by a 7-bit-group number that
 * runs to 64 bits (0xfe, eight 0xff, 0x01: 2^64 - 2, a zigzag difference of 2^63 - 1). */
static void damage_block(unsigned char *block, uint64_t bytes)
{
    if (bytes < 10)
        return;
    block[0] = 0xfe;
    memset(block + 1, 0xff, 8);
    block[9] = 0x01;
}

static ic_result fake_allgather(void *user, const void *send, void *recv, const uint64_t *counts)
{
    rank_link *l = user;
    transport *t = l->t;
    /* send may lie inside recv (in place): copy it out before anyone writes. */
    void *own = malloc(counts[l->rank] ? counts[l->rank] : 1);
    memcpy(own, send, counts[l->rank]);
    t->published[l->rank] = own;
    pthread_barrier_wait(&t->barrier);
    uint64_t at = 0;
    for (int r = 0; r < t->size; ++r) {
        memcpy((char *)recv + at, t->published[r], counts[r]);
        if (l->allgathers + 1 == l->damage_allgather && r == (l->rank + 1) % t->size)
            damage_block((unsigned char *)recv + at, counts[r]);
        at += counts[r];
    }
    ++l->allgathers;
    pthread_barrier_wait(&t->barrier);
    free(own);
    return IC_OK;
}

static ic_result fake_sum(void *user, double *values, uint64_t count)
{
    rank_link *l = user;
    transport *t = l->t;
    double *total = calloc(count ? count : 1, sizeof *total);
    t->published[l->rank] = values;
    pthread_barrier_wait(&t->barrier);
    for (int r = 0; r < t->size; ++r)
        for (uint64_t i = 0; i < count; ++i)
            total[i] += ((const double *)t->published[r])[i];
    pthread_barrier_wait(&t->barrier);
    memcpy(values, total, sizeof *total * count);
    free(total);
    ++l->sums;
    return l->fail_sum_from > 0 && l->sums >= l->fail_sum_from ? IC_ERR_IO : IC_OK;
}

static ic_result fake_broadcast(void *user, void *buf, uint64_t bytes, int root)
{
    rank_link *l = user;
    transport *t = l->t;
    if (l->rank == root)
        t->published[root] = buf;
    pthread_barrier_wait(&t->barrier);
    if (l->rank != root)
        memcpy(buf, t->published[root], bytes);
    pthread_barrier_wait(&t->barrier);
    return IC_OK;
}

/* All-to-all: every rank publishes its buffer and its counts, then reads its block of each. */
static const uint64_t *published_counts[MAX_RANKS];
static ic_result fake_alltoall(void *user, const void *send, const uint64_t *send_counts, void *recv,
                               const uint64_t *recv_counts)
{
    rank_link *l = user;
    transport *t = l->t;
    t->published[l->rank] = send;
    published_counts[l->rank] = send_counts;
    pthread_barrier_wait(&t->barrier);
    uint64_t put = 0;
    for (int q = 0; q < t->size; ++q) {
        uint64_t skip = 0;
        for (int k = 0; k < l->rank; ++k)
            skip += published_counts[q][k];
        if (published_counts[q][l->rank] != recv_counts[q])
            fprintf(stderr, "rank %d expects %llu bytes from rank %d, which sends %llu\n", l->rank,
                    (unsigned long long)recv_counts[q], q, (unsigned long long)published_counts[q][l->rank]);
        memcpy((char *)recv + put, (const char *)t->published[q] + skip, recv_counts[q]);
        put += recv_counts[q];
    }
    pthread_barrier_wait(&t->barrier);
    return IC_OK;
}

/* Messages: a post copies the bytes into the receiver's mailbox at once, so every send is done when
 * posted; take pops the oldest. */
static ic_result fake_post(void *user, int to, const void *buf, uint64_t bytes, void **request)
{
    rank_link *l = user;
    transport *t = l->t;
    message *m = malloc(sizeof *m + bytes);
    if (!m)
        return IC_ERR_OOM;
    m->next = NULL;
    m->from = l->rank;
    m->bytes = bytes;
    memcpy(m->data, buf, bytes);
    pthread_mutex_lock(&t->lock);
    if (t->last[to])
        t->last[to]->next = m;
    else
        t->first[to] = m;
    t->last[to] = m;
    ++t->messages;
    pthread_cond_broadcast(&t->arrived);
    pthread_mutex_unlock(&t->lock);
    *request = l;
    return IC_OK;
}

static ic_result fake_sent(void *user, void *request, int wait, int *done)
{
    (void)user;
    (void)wait;
    *done = request != NULL;
    return IC_OK;
}

/* The message a take hands over: the oldest, except over a slow link, whose messages are not there for a
 * take that does not wait, and are handed to one that waits only once no other has arrived for
 * slow_seconds. MPI keeps the messages between two ranks in order but promises nothing across senders, so
 * this is a transport the library must work with: a message sent earlier by one rank may arrive after one
 * sent later by another. */
static message *next_message(transport *t, int to, int wait)
{
    message *prev = NULL, *m = t->first[to];
    const int slow = t->slow_seconds > 0.0 && to == t->slow_to;
    for (; slow && m && m->from == t->slow_from; prev = m, m = m->next) {
    }
    if (!m && slow && wait && t->first[to]) {
        struct timespec until;
        clock_gettime(CLOCK_REALTIME, &until);
        double s = (double)until.tv_nsec * 1e-9 + t->slow_seconds;
        until.tv_sec += (time_t)s;
        until.tv_nsec = (long)((s - (double)(time_t)s) * 1e9);
        int arrived = t->messages;
        while (t->messages == arrived && pthread_cond_timedwait(&t->arrived, &t->lock, &until) == 0) {
        }
        if (t->messages != arrived)
            return next_message(t, to, wait); /* another came: look again */
        prev = NULL;
        m = t->first[to];
    }
    if (!m)
        return NULL;
    if (prev)
        prev->next = m->next;
    else
        t->first[to] = m->next;
    if (t->last[to] == m)
        t->last[to] = prev;
    return m;
}

static ic_result fake_take(void *user, void *buf, uint64_t room, int wait, int *from, uint64_t *bytes)
{
    rank_link *l = user;
    transport *t = l->t;
    pthread_mutex_lock(&t->lock);
    while (wait && !t->first[l->rank])
        pthread_cond_wait(&t->arrived, &t->lock);
    message *m = next_message(t, l->rank, wait);
    pthread_mutex_unlock(&t->lock);
    *bytes = 0;
    if (!m)
        return IC_OK;
    ic_result r = m->bytes <= room ? IC_OK : IC_ERR_IO;
    if (r == IC_OK) {
        memcpy(buf, m->data, m->bytes);
        *bytes = m->bytes;
        *from = m->from;
    }
    free(m);
    return r;
}

/* ---- one job: `size` ranks, each a thread running ic_render or ic_points_compute */
typedef struct rank_job {
    rank_link link;
    ic_comm comm;
    const ic_scene *scene;
    ic_render_options opt;      /* render (when points is NULL) */
    ic_image img;
    ic_render_stats st;
    const ic_sensor_point *points; /* sensor points instead of a render */
    uint32_t point_count;
    ic_points_options popt;
    ic_point_result *results;
    ic_points_stats pst;
    const ic_record *records;      /* cache insertions instead of a render: batches of batch_size */
    uint32_t record_count, batch_size;
    ic_cache *cache;
    ic_result r;
    ic_error err;
} rank_job;

static void *run_rank(void *p)
{
    rank_job *j = p;
    if (j->records) {
        ic_cache_params cp = {0};
        cp.threads = 1;
        j->r = ic_cache_create(&cp, &j->cache, &j->err);
        if (j->r == IC_OK)
            ic_cache_set_comm(j->cache, &j->comm);
        for (uint32_t at = 0; j->r == IC_OK && at < j->record_count; at += j->batch_size) {
            uint32_t n = j->record_count - at < j->batch_size ? j->record_count - at : j->batch_size;
            j->r = ic_cache_insert_batch(j->cache, j->records + at, n, NULL, &j->err);
        }
    } else if (j->points) {
        j->popt.comm = &j->comm;
        j->r = ic_points_compute(j->scene, j->points, j->point_count, &j->popt, j->results, &j->pst, &j->err);
    } else {
        j->opt.comm = &j->comm;
        j->r = ic_render(j->scene, &j->opt, &j->img, &j->st, &j->err);
    }
    return NULL;
}

/* Runs the job on `size` ranks over a transport whose messages from rank slow_from to rank slow_to arrive
 * last (slow_seconds > 0; next_message); jobs[r] must hold its options (and, for points, its buffers). */
static int run_job_slow(rank_job *jobs, int size, int slow_from, int slow_to, double slow_seconds)
{
    transport t;
    memset(&t, 0, sizeof t);
    t.size = size;
    t.slow_from = slow_from;
    t.slow_to = slow_to;
    t.slow_seconds = slow_seconds;
    pthread_barrier_init(&t.barrier, NULL, (unsigned)size);
    pthread_mutex_init(&t.lock, NULL);
    pthread_cond_init(&t.arrived, NULL);
    pthread_t th[MAX_RANKS];
    for (int r = 0; r < size; ++r) {
        jobs[r].link.t = &t;
        jobs[r].link.rank = r;
        /* Two ranks with the required operations alone (the library emulates the all-to-all with the
         * all-gather and exchanges finished tiles at the end), more with all-to-all and messages too. */
        int full = size > 2;
        jobs[r].comm = (ic_comm){.rank = r, .size = size, .user = &jobs[r].link, .allgather = fake_allgather,
                                 .sum = fake_sum, .broadcast = fake_broadcast,
                                 .alltoall = full ? fake_alltoall : NULL, .post = full ? fake_post : NULL,
                                 .sent = full ? fake_sent : NULL, .take = full ? fake_take : NULL};
        pthread_create(&th[r], NULL, run_rank, &jobs[r]);
    }
    int ok = 1;
    for (int r = 0; r < size; ++r) {
        pthread_join(th[r], NULL);
        if (jobs[r].r != IC_OK) {
            fprintf(stderr, "rank %d of %d: %s\n", r, size, jobs[r].err.message);
            ok = 0;
        }
    }
    pthread_barrier_destroy(&t.barrier);
    for (int r = 0; r < size; ++r)
        CHECK(!t.first[r], "a message to rank %d of %d was never taken", r, size);
    if (ok && size > 2 && jobs[0].opt.spp > 0 && !jobs[0].points && !jobs[0].records && !(jobs[0].opt.time_budget > 0.0))
        CHECK(t.messages > 0, "%d ranks sent no finished tiles as messages", size);
    pthread_mutex_destroy(&t.lock);
    pthread_cond_destroy(&t.arrived);
    return ok;
}

static int run_job(rank_job *jobs, int size) { return run_job_slow(jobs, size, 0, 0, 0.0); }

static int same_image(const ic_image *a, const ic_image *b)
{
    return a->width == b->width && a->height == b->height &&
           !memcmp(a->rgb, b->rgb, sizeof *a->rgb * 3 * (size_t)a->width * a->height);
}

/* Renders with opt on one process (2 threads) and on each rank count (1 thread per rank): the same bits on
 * every rank, the same records per pass, and the ranks' shares adding up to the whole. */
static void check_render(const char *what, const ic_scene *scene, ic_render_options opt, int check_equal)
{
    ic_image ref = {0};
    ic_render_stats ref_st;
    ic_error err = {0};
    opt.threads = 2;
    CHECK(ic_render(scene, &opt, &ref, &ref_st, &err) == IC_OK, "%s: one process: %s", what, err.message);
    static const int sizes[] = {2, 3, 5};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; ++k) {
        int size = sizes[k];
        rank_job jobs[MAX_RANKS];
        memset(jobs, 0, sizeof jobs);
        for (int r = 0; r < size; ++r) {
            jobs[r].scene = scene;
            jobs[r].opt = opt;
            jobs[r].opt.threads = 1;
        }
        int ok = run_job(jobs, size);
        CHECK(ok, "%s: %d ranks failed", what, size);
        if (!ok)
            continue;
        uint64_t gathered = 0, samples = 0;
        for (int r = 0; r < size; ++r) {
            CHECK(same_image(&jobs[r].img, &jobs[0].img), "%s: rank %d of %d has another image than rank 0", what,
                  r, size);
            CHECK(jobs[r].st.ranks == size, "%s: stats say %d ranks, not %d", what, jobs[r].st.ranks, size);
            gathered += jobs[r].st.rank_records_gathered;
            samples += jobs[r].st.rank_pixel_samples;
        }
        uint64_t want = check_equal ? ref_st.rank_pixel_samples : (uint64_t)jobs[0].st.spp * SIZE * SIZE;
        CHECK(samples == want, "%s, %d ranks: %llu pixel samples, expected %llu", what, size,
              (unsigned long long)samples, (unsigned long long)want);
        if (check_equal) {
            CHECK(same_image(&jobs[0].img, &ref), "%s, %d ranks: the image differs from one process's", what, size);
            /* The job's rays: each counted once, by the process that traced it or, where every process
             * traces it alike, by one of them (the hit stage's probes were counted on every rank). */
            CHECK(jobs[0].st.rays == ref_st.rays && jobs[0].st.gather_rays == ref_st.gather_rays,
                  "%s, %d ranks: %llu rays (%llu gathering), one process %llu (%llu)", what, size,
                  (unsigned long long)jobs[0].st.rays, (unsigned long long)jobs[0].st.gather_rays,
                  (unsigned long long)ref_st.rays, (unsigned long long)ref_st.gather_rays);
            CHECK(jobs[0].st.cached_emitters == ref_st.cached_emitters,
                  "%s, %d ranks: %u emitting triangles carried by the records, one process %u", what, size,
                  jobs[0].st.cached_emitters, ref_st.cached_emitters);
            CHECK(jobs[0].st.records == ref_st.records && jobs[0].st.passes == ref_st.passes &&
                      !memcmp(jobs[0].st.records_per_pass, ref_st.records_per_pass, sizeof ref_st.records_per_pass),
                  "%s, %d ranks: %u records in %d passes, one process %u in %d", what, size, jobs[0].st.records,
                  jobs[0].st.passes, ref_st.records, ref_st.passes);
            CHECK(!opt.ic.load_cache ? gathered == ref_st.rank_records_gathered : gathered == 0,
                  "%s, %d ranks: %llu records gathered in all, one process %llu", what, size,
                  (unsigned long long)gathered, (unsigned long long)ref_st.rank_records_gathered);
        }
        for (int r = 0; r < size; ++r)
            ic_image_free(&jobs[r].img);
    }
    ic_image_free(&ref);
}

/* check_render on the Cornell box at width x height. */
static void check_render_at(const char *what, int width, int height, ic_render_options opt)
{
    ic_scene_load_options lo = {0};
    lo.width = width;
    lo.height = height;
    ic_scene *scene = NULL;
    ic_error err = {0};
    CHECK(ic_scene_load(SCENE, &lo, &scene, &err) == IC_OK, "%s: %s", what, err.message);
    if (scene)
        check_render(what, scene, opt, 1);
    ic_scene_free(scene);
}

/* The indirect AOV is a second film right after the image, with no collective operation between them, so
 * both stream their finished tiles. Over a slow link from rank 2 to rank 1, rank 1 still waits for rank 2's
 * last tile of the image when rank 0 (which has all of the image) already sends the AOV's first: each
 * stream must take only its own tiles, so the image and the AOV are still one process's. */
static void check_streams_in_a_row(const ic_scene *scene, ic_render_options opt)
{
    ic_render_aovs ref_aovs = {0};
    ref_aovs.want_indirect = 1;
    opt.aovs = &ref_aovs;
    opt.threads = 2;
    ic_image ref = {0};
    ic_render_stats ref_st;
    ic_error err = {0};
    CHECK(ic_render(scene, &opt, &ref, &ref_st, &err) == IC_OK, "image and AOV, one process: %s", err.message);
    enum { RANKS = 3 };
    rank_job jobs[RANKS];
    ic_render_aovs aovs[RANKS];
    memset(jobs, 0, sizeof jobs);
    memset(aovs, 0, sizeof aovs);
    for (int r = 0; r < RANKS; ++r) {
        aovs[r].want_indirect = 1;
        jobs[r].scene = scene;
        jobs[r].opt = opt;
        jobs[r].opt.aovs = &aovs[r];
        jobs[r].opt.threads = 1;
    }
    CHECK(run_job_slow(jobs, RANKS, 2, 1, 0.3), "image and AOV, %d ranks over a slow link: failed", RANKS);
    for (int r = 0; r < RANKS; ++r) {
        CHECK(same_image(&jobs[r].img, &ref), "image and AOV over a slow link: rank %d's image differs from one "
              "process's", r);
        CHECK(aovs[r].indirect.rgb && same_image(&aovs[r].indirect, &ref_aovs.indirect),
              "image and AOV over a slow link: rank %d's indirect AOV differs from one process's", r);
        ic_image_free(&jobs[r].img);
        ic_image_free(&aovs[r].indirect);
    }
    ic_image_free(&ref);
    ic_image_free(&ref_aovs.indirect);
}

/* A sum that fails on every rank (fault injection: the n-th and every later one, for each n until the
 * render no longer meets one) fails the render on every rank, and the image, "allocated here", is never
 * freed unless the film made it: the caller's ic_image may hold anything (here a pointer that free
 * aborts on). Adaptive sampling at 3 ranks: sums end the pilot's stream and share out the second pass. */
static void check_failed_sums(const ic_scene *scene)
{
    ic_render_options opt = {0};
    opt.integrator = IC_INTEGRATOR_PT;
    opt.spp = 8;
    opt.adaptive_sampling = IC_CACHE_ON;
    opt.threads = 1;
    enum { RANKS = 3 };
    float not_allocated[3];
    int failed_at = 0;
    for (int n = 1; n < 40; ++n) {
        rank_job jobs[RANKS];
        memset(jobs, 0, sizeof jobs);
        for (int r = 0; r < RANKS; ++r) {
            jobs[r].scene = scene;
            jobs[r].opt = opt;
            jobs[r].link.fail_sum_from = n;
            jobs[r].img.rgb = not_allocated;
        }
        int ok = run_job(jobs, RANKS);
        for (int r = 0; r < RANKS; ++r) {
            CHECK((jobs[r].r == IC_OK) == ok, "sums failing from the %d-th: rank %d %s, another not", n, r,
                  ok ? "failed" : "went on");
            /* Failed, the image is the caller's pointer, none, or (a sum after the film failed) the film's. */
            if (jobs[r].img.rgb != not_allocated)
                ic_image_free(&jobs[r].img);
        }
        if (ok)
            break;
        failed_at = n;
    }
    CHECK(failed_at >= 2, "the render met %d sums: nothing tested", failed_at);
}

/* The first `count` (at most 40) of a grid of sensor points over the Cornell box's floor on `ranks` ranks: the
 * results, rays, records and hit records of one process. */
static void check_points(const ic_scene *scene, ic_integrator integrator, uint32_t count, int ranks)
{
    enum { N = 40 };
    ic_sensor_point pts[N];
    for (int i = 0; i < N; ++i) {
        pts[i].position = (ic_vec3){-0.8f + 1.6f * (float)(i % 8) / 7.0f, 0.1f + 0.3f * (float)(i / 8), 0.1f};
        pts[i].normal = (ic_vec3){0.0f, 1.0f, 0.0f};
    }
    ic_points_options po = {0};
    po.integrator = integrator;
    po.samples = 32;
    po.light_samples = 32;
    po.ic.gather.theta_strata = 8;
    po.ic.gather.phi_strata = 25;
    po.threads = 2;
    ic_point_result ref[N];
    ic_error err = {0};
    ic_points_stats ref_st;
    CHECK(ic_points_compute(scene, pts, count, &po, ref, &ref_st, &err) == IC_OK, "points, one process: %s",
          err.message);
    static ic_point_result res[MAX_RANKS][N];
    rank_job jobs[MAX_RANKS];
    memset(jobs, 0, sizeof jobs);
    memset(res, 0, sizeof res);
    for (int r = 0; r < ranks; ++r) {
        jobs[r].scene = scene;
        jobs[r].points = pts;
        jobs[r].point_count = count;
        jobs[r].popt = po;
        jobs[r].popt.threads = 1;
        jobs[r].results = res[r];
    }
    const char *what = integrator == IC_INTEGRATOR_IC ? "cache" : "path tracer";
    CHECK(run_job(jobs, ranks), "points (%s), %u of them: %d ranks failed", what, count, ranks);
    for (int r = 0; r < ranks; ++r) {
        CHECK(!memcmp(res[r], ref, sizeof *ref * count), "points (%s), %u of them, rank %d of %d: results differ "
              "from one process's", what, count, r, ranks);
        /* the hit stage's probe rays on a block each: counted once in the job's rays */
        CHECK(jobs[r].pst.rays == ref_st.rays && jobs[r].pst.records == ref_st.records &&
                  jobs[r].pst.hit_records == ref_st.hit_records,
              "points (%s), %u of them, rank %d of %d: %llu rays, %u records, %u hit records; one process %llu, %u, %u",
              what, count, r, ranks, (unsigned long long)jobs[r].pst.rays,
              jobs[r].pst.records, jobs[r].pst.hit_records, (unsigned long long)ref_st.rays, ref_st.records,
              ref_st.hit_records);
    }
}

/* n records on a 4 x 4 floor, at random places with random harmonic mean distances (seed): close enough
 * for the clamps to lower many radii. */
static void scattered_records(ic_record *recs, int n, uint64_t seed)
{
    ic_rng rng = ic_rng_make(seed, 0, 0, 0);
    for (int i = 0; i < n; ++i) {
        memset(&recs[i], 0, sizeof recs[i]);
        recs[i].position = (ic_vec3){4.0f * ic_rng_float(&rng), 0.0f, 4.0f * ic_rng_float(&rng)};
        recs[i].normal = (ic_vec3){0.0f, 1.0f, 0.0f};
        recs[i].irradiance = (ic_vec3){1.0f, 1.0f, 1.0f};
        recs[i].harmonic_mean_dist = 0.05f + 2.0f * ic_rng_float(&rng);
    }
}

/* Insertions into copies of one cache shared by 3 ranks (ic_cache_set_comm: each clamps a block of every
 * batch's validity radii): every copy's records, radii included, equal one process's. Batches of 300 give
 * every rank a block above the clamp's threaded size, of 7 below it, of 1 some ranks with none. */
static void check_cache_insertions(void)
{
    enum { N = 900 };
    static ic_record recs[N];
    scattered_records(recs, N, 3);
    static const uint32_t batches[] = {300, 7, 1};
    for (size_t b = 0; b < sizeof batches / sizeof batches[0]; ++b) {
        uint32_t count = batches[b] == 1 ? 40 : N;
        rank_job one[1], jobs[3];
        memset(one, 0, sizeof one);
        memset(jobs, 0, sizeof jobs);
        for (int r = 0; r < 3; ++r) {
            jobs[r].records = recs;
            jobs[r].record_count = count;
            jobs[r].batch_size = batches[b];
        }
        one[0] = jobs[0];
        CHECK(run_job(one, 1) && run_job(jobs, 3), "cache insertions in batches of %u failed", batches[b]);
        int differ = 0, clamped = 0;
        for (uint32_t i = 0; i < count && one[0].cache; ++i) {
            ic_record a, c;
            ic_cache_get_record(one[0].cache, i, &a);
            clamped += a.radius < a.harmonic_mean_dist;
            for (int r = 0; r < 3; ++r) {
                if (!jobs[r].cache || ic_cache_get_record(jobs[r].cache, i, &c) != IC_OK) {
                    ++differ;
                    continue;
                }
                differ += memcmp(&a, &c, sizeof a) != 0;
            }
        }
        CHECK(differ == 0, "cache insertions in batches of %u on 3 ranks: %d records differ from one process's",
              batches[b], differ);
        CHECK(clamped > 0, "cache insertions in batches of %u: no radius was clamped (nothing tested)", batches[b]);
        ic_cache_destroy(one[0].cache);
        for (int r = 0; r < 3; ++r)
            ic_cache_destroy(jobs[r].cache);
    }
}

/* A batch inserted by 3 ranks whose third all-gather (the neighbour lists: after the validity radii and the
 * lists' lengths) delivers each rank the next rank's block damaged: a difference that runs to 64 bits, which
 * no list entry needs (33 bits at most). Every rank refuses the block (IC_ERR_IO) instead of adding it to a
 * record's index, where it overflowed a signed 64-bit sum (undefined behaviour, caught by the sanitizer
 * build). */
static void check_damaged_lists(void)
{
    enum { N = 300 };
    static ic_record recs[N];
    scattered_records(recs, N, 5);
    rank_job jobs[3];
    memset(jobs, 0, sizeof jobs);
    for (int r = 0; r < 3; ++r) {
        jobs[r].records = recs;
        jobs[r].record_count = jobs[r].batch_size = N;
        jobs[r].link.damage_allgather = 3;
    }
    CHECK(!run_job(jobs, 3), "3 ranks accepted damaged neighbour lists");
    for (int r = 0; r < 3; ++r) {
        CHECK(jobs[r].r == IC_ERR_IO && strstr(jobs[r].err.message, "shared their clamps"),
              "rank %d of 3, given a damaged block of neighbour lists: %s (%s)", r, ic_result_name(jobs[r].r),
              jobs[r].err.message);
        ic_cache_destroy(jobs[r].cache);
    }
}

/* ---- the world stage's clustering over several processes: each holds a share of the candidates, and
 * every one gets what ic_world_select gives for them all at once, bit for bit */
typedef struct world_rank {
    rank_link link;
    ic_comm comm;
    ic_candidate *own;
    uint32_t own_count;
    float max_box;
    ic_candidate *out;
    uint32_t kept;
    uint64_t total;
    double visited;
    ic_result r;
    ic_error err;
} world_rank;

static const ic_vec3 WORLD_LO = {-1.0f, -1.0f, -1.0f}, WORLD_HI = {1.0f, 1.0f, 1.0f};

static void *run_world_rank(void *p)
{
    world_rank *w = p;
    w->r = ic_world_select_shared(&w->comm, w->own, w->own_count, WORLD_LO, WORLD_HI, w->max_box, 3, 30.0f, &w->out,
                                  &w->kept, &w->total, &w->visited, &w->err);
    return NULL;
}

/* count candidates from `make` (index → candidate), dealt to `size` ranks in blocks of `deal`. */
/* The same n candidates, bit for bit, field by field: the 4 bytes of padding before key are nobody's to set
 * (the candidates are filled field by field), so a memcmp of the structs read bytes never written. */
static int same_candidates(const ic_candidate *a, const ic_candidate *b, uint32_t n)
{
    for (uint32_t i = 0; i < n; ++i)
        if (memcmp(&a[i].p, &b[i].p, sizeof a[i].p) || memcmp(&a[i].n, &b[i].n, sizeof a[i].n) ||
            memcmp(&a[i].footprint, &b[i].footprint, sizeof a[i].footprint) || a[i].key != b[i].key)
            return 0;
    return 1;
}

static void check_world(const char *what, const ic_candidate *all, uint32_t count, float max_box, int size, int deal,
                        int alltoall)
{
    ic_candidate *want = malloc(sizeof *want * count);
    memcpy(want, all, sizeof *want * count);
    uint32_t kept = 0;
    CHECK(ic_world_select(want, count, WORLD_LO, WORLD_HI, max_box, 3, 30.0f, &kept) == IC_OK, "%s: select", what);
    transport t;
    memset(&t, 0, sizeof t);
    t.size = size;
    pthread_barrier_init(&t.barrier, NULL, (unsigned)size);
    pthread_mutex_init(&t.lock, NULL);
    pthread_cond_init(&t.arrived, NULL);
    world_rank w[MAX_RANKS];
    pthread_t th[MAX_RANKS];
    memset(w, 0, sizeof w);
    for (int r = 0; r < size; ++r) {
        w[r].own = malloc(sizeof *w[r].own * (count + 1));
        for (uint32_t i = 0; i < count; ++i)
            if ((int)(i / (uint32_t)deal) % size == r)
                w[r].own[w[r].own_count++] = all[i];
        w[r].visited = r + 1.0;
        w[r].max_box = max_box;
        w[r].link = (rank_link){.t = &t, .rank = r};
        w[r].comm = (ic_comm){.rank = r, .size = size, .user = &w[r].link, .allgather = fake_allgather,
                              .sum = fake_sum, .broadcast = fake_broadcast, .alltoall = alltoall ? fake_alltoall : NULL};
        pthread_create(&th[r], NULL, run_world_rank, &w[r]);
    }
    for (int r = 0; r < size; ++r)
        pthread_join(th[r], NULL);
    pthread_barrier_destroy(&t.barrier);
    for (int r = 0; r < size; ++r) {
        CHECK(w[r].r == IC_OK, "%s, %d ranks: rank %d failed: %s", what, size, r, w[r].err.message);
        CHECK(w[r].total == count && w[r].visited == size * (size + 1) / 2.0,
              "%s, %d ranks: rank %d counted %llu candidates and %g visited, not %u and %g", what, size, r,
              (unsigned long long)w[r].total, w[r].visited, count, size * (size + 1) / 2.0);
        CHECK(w[r].kept == kept && same_candidates(w[r].out, want, kept),
              "%s, %d ranks%s: rank %d kept %u candidates, one process %u, or not the same", what, size,
              alltoall ? "" : " (emulated all-to-all)", r, w[r].kept, kept);
        free(w[r].out);
    }
    free(want);
}

static void test_world_select(void)
{
    enum { COUNT = 4000 };
    ic_candidate *c = malloc(sizeof *c * COUNT);
    ic_rng rng = ic_rng_make(23, 0, 0, 0);
    /* Three quarters in a dense patch (no gap between Morton neighbours inside it at the larger boxes, so
     * clusters cross the ranges' ends and heads run over whole ranges), the rest scattered. The normal
     * follows the position (one direction where x > 0.5, another where y > 0.5, a third elsewhere), so a
     * cluster's second and third kept candidates lie far along the order: a cluster cut short at a
     * range's end loses them. */
    for (uint32_t i = 0; i < COUNT; ++i) {
        float s = i % 4 ? 0.05f : 1.0f;
        c[i].p = (ic_vec3){s * (2.0f * ic_rng_float(&rng) - 1.0f), s * (2.0f * ic_rng_float(&rng) - 1.0f),
                           i % 4 ? 0.0f : 2.0f * ic_rng_float(&rng) - 1.0f};
        int d = c[i].p.x > 0.5f ? 0 : c[i].p.y > 0.5f ? 1 : 2;
        c[i].n = (ic_vec3){d == 0 ? 1.0f : 0.0f, d == 1 ? 1.0f : 0.0f, d == 2 ? 1.0f : 0.0f};
        c[i].footprint = 0.0f;
        c[i].key = (uint64_t)i * 2654435761u;
    }
    const float boxes[] = {0.0f, 0.01f, 0.2f, 5.0f};
    for (int b = 0; b < 4; ++b)
        for (int size = 2; size <= MAX_RANKS; ++size) {
            char what[64];
            snprintf(what, sizeof what, "world select, box %g", boxes[b]);
            check_world(what, c, COUNT, boxes[b], size, 7, size != 4);
        }
    /* Every candidate in one Morton bucket: all ranges but one empty. */
    for (uint32_t i = 0; i < COUNT; ++i)
        c[i].p = (ic_vec3){0.3f + 1e-4f * ic_rng_float(&rng), 0.3f, 0.3f};
    check_world("world select, one bucket", c, COUNT, 1e-5f, 5, 1, 1);
    check_world("world select, no candidates", c, 0, 1e-5f, 3, 1, 1);
    free(c);
}

int main(void)
{
    test_world_select();
    ic_error err = {0};
    ic_scene *scene = NULL;
    ic_scene_load_options lo = {0};
    lo.width = SIZE;
    lo.height = SIZE;
    if (ic_scene_load(SCENE, &lo, &scene, &err) != IC_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    ic_render_options ic = {0};
    ic.integrator = IC_INTEGRATOR_IC;
    ic.spp = 8; /* adaptive sampling: the pilot's sums are combined before the allocation */
    ic.ic.gather.theta_strata = 8;
    ic.ic.gather.phi_strata = 25;
    ic.ic.save_cache = CACHE_FILE;
    check_render("cache, batch", scene, ic, 1);
    ic.ic.save_cache = NULL;

    /* A tall image: each rank's band of shading points (its rows and IC_SCREEN_HALO on either side) leaves
     * rows out, whose points come from ic_ic_gbuffer_point (the candidates, the hit stage's probes, the
     * large-emitter pilot, the view extent, the final render's light blocks). */
    check_render_at("cache, batch, a 12x300 image", 12, 300, ic);
    /* More ranks than rows (9x2): ranks with no rows of their own make no coverage candidates and hold none of
     * the need maps, and each traces a few dozen of the hit stage's 288 probes. */
    check_render_at("cache, batch, a 9x2 image", 9, 2, ic);

    /* A large emitter that the records carry: the emitters' hemisphere shares are measured on a block of
     * the shading points per rank, and every rank must make one process's choice. */
    test_write_window_scene(IC_TEST_TMP);
    ic_scene *window = NULL;
    CHECK(ic_scene_load(IC_TEST_TMP "/window.json", NULL, &window, &err) == IC_OK, "%s", err.message);
    if (window) {
        /* the default hemisphere rays: with fewer, light sampling would be the better estimator */
        ic_render_options window_ic = ic;
        window_ic.ic.save_cache = NULL;
        window_ic.spp = 2;
        window_ic.ic.gather.theta_strata = window_ic.ic.gather.phi_strata = 0;
        ic_image img = {0};
        ic_render_stats st;
        CHECK(ic_render(window, &window_ic, &img, &st, &err) == IC_OK && st.cached_emitters > 0,
              "the window's emitter is not carried by the records (%u triangles; %s)", st.cached_emitters, err.message);
        ic_image_free(&img);
        check_render("cache, batch, a window's light carried by the records", window, window_ic, 1);
        ic_scene_free(window);
    }

    ic_render_options adaptive = ic;
    adaptive.ic.strategy = IC_STRATEGY_ADAPTIVE;
    check_render("cache, adaptive", scene, adaptive, 1);

    ic_render_options loaded = ic;
    loaded.ic.load_cache = CACHE_FILE;
    check_render("cache, loaded from a file", scene, loaded, 1);

    /* The Hessian's fields travel with the records only when the error metric fills them. */
    ic_render_options hessian = ic;
    hessian.ic.error = IC_ERROR_HESSIAN;
    hessian.ic.record_shape = IC_SHAPE_ELLIPTICAL;
    check_render("cache, Hessian error, elliptical records", scene, hessian, 1);

    ic_render_options pt = {0};
    pt.integrator = IC_INTEGRATOR_PT;
    pt.spp = 4;
    check_render("path tracer", scene, pt, 1);
    check_streams_in_a_row(scene, ic);
    check_failed_sums(scene);

    /* A time budget: passes sized by rank 0's clock, so every rank holds the same image (which depends on
     * the clock, so not one process's). */
    ic_render_options timed = pt;
    timed.spp = 0;
    timed.time_budget = 0.3;
    check_render("path tracer, time budget", scene, timed, 0);
    /* The cache under a time budget: construction stops at the pass rank 0's clock says, on every rank. */
    ic_render_options timed_ic = ic;
    timed_ic.spp = 0;
    timed_ic.time_budget = 0.5;
    check_render("cache, time budget", scene, timed_ic, 0);

    /* Lazy construction cannot be shared: refused, on every rank. */
    rank_job jobs[2];
    memset(jobs, 0, sizeof jobs);
    for (int r = 0; r < 2; ++r) {
        jobs[r].scene = scene;
        jobs[r].opt = ic;
        jobs[r].opt.ic.strategy = IC_STRATEGY_LAZY;
    }
    CHECK(!run_job(jobs, 2) && jobs[0].r == IC_ERR_UNSUPPORTED && strstr(jobs[0].err.message, "lazy"),
          "lazy under 2 ranks: not refused with a message naming it (%s)", jobs[0].err.message);

    check_points(scene, IC_INTEGRATOR_IC, 40, 3);
    check_points(scene, IC_INTEGRATOR_PT, 40, 3);
    /* More ranks than sensors: ranks without a sensor of their own, 32 hit-stage probes over 5 ranks, and one
     * shading point for the large emitters' shares, on rank 0 alone. */
    check_points(scene, IC_INTEGRATOR_IC, 2, 5);
    check_cache_insertions();
    check_damaged_lists();
    ic_scene_free(scene);
    remove(CACHE_FILE);
    TEST_MAIN_END();
}
