/*
 * test_main.c - the standalone simulator's runtime (gen_rt_main.c): the
 * command line, the CSV tables and the run loop, on a model of its own.
 *
 * The model: an oscillator q' = u, u' = -k q (k = p[0]) whose "simulate"
 * writes the exact solution q = q0 cos(w t) + u0/w sin(w t) on the output
 * grid (w = sqrt(k)), with one multiplier 2 q, one constraint residual
 * q + u, the energy (u^2 + k q^2)/2, one reaction force u and one output
 * q r. p[1] = 1 makes the run fail after 3 rows, p[1] = 2 the constraints
 * at the third row; an input r < 0 makes the output fail (nan). Events are
 * the sign changes of x[which] - level between two rows.
 */
#include <stdlib.h>

#include "gen_rt_main.h"
#include "test_common.h"

#define OUT_CSV "test_main_out.csv"
#define EV_CSV "test_main_events.csv"
#define IN_CSV "test_main_in.csv"

static const char *const x_names[2] = {"q", "u"};
static const char *const r_names[1] = {"F"};
static const char *const p_names[2] = {"k", "fail"};
static const char *const y_names[1] = {"qF"};
static const char *const a_names[1] = {"R"};
static const char *const i_names[3] = {"q", "u", ""};
static const gen_rt_real p_default[2] = {4, 0};

static int n_calls;               /* simulate calls */
static gen_rt_main_run last_run;  /* the last run simulate saw */
static double last_x_op0 = -1;    /* and its x_op[0] */

static void opts_default(gen_rt_main_options *o)
{
    o->method = 0; o->project = 1; o->every = 1; o->final_only = 0;
    o->rtol = 1e-8; o->atol = 1e-10;
}

static int consistent(const void *p, void *x)
{
    (void)p;
    ((gen_rt_real *)x)[1] += 1;   /* visible: u0 + 1 */
    return 0;
}

static int linearize(const void *x, const void *r, const void *p, void *A, void *B)
{
    gen_rt_real *a = (gen_rt_real *)A, *b = (gen_rt_real *)B;
    (void)x; (void)r;
    a[0] = 0; a[1] = 1; a[2] = -((const gen_rt_real *)p)[0]; a[3] = 0;
    b[0] = 0; b[1] = 1;
    return 0;
}

static int rows_of(double t_end, double dt)
{
    double n = t_end / dt;
    return n > 1e7 ? -1 : (int)(n + 0.5) + 1;
}

static void exact(double q0, double u0, double k, double t, double *q, double *u)
{
    double w = sqrt(k);
    *q = q0 * cos(w * t) + u0 / w * sin(w * t);
    *u = -q0 * w * sin(w * t) + u0 * cos(w * t);
}

/* the input at t: the constant, or the table's row (zero-order hold) */
static double input_at(const gen_rt_main_run *run, double t)
{
    const gen_rt_real *tt = (const gen_rt_real *)run->t_table;
    int i;
    if (run->n_table == 0) return (double)((const gen_rt_real *)run->r)[0];
    for (i = run->n_table - 1; i > 0 && (double)tt[i] > t; --i) {}
    return (double)((const gen_rt_real *)run->r_table)[i];
}

static int simulate(const gen_rt_main_run *run, const void *x0v, void *t_out, void *x_out,
                    void *lam_out, void *r_out, gen_rt_main_stats *stats)
{
    const gen_rt_real *x0 = (const gen_rt_real *)x0v, *p = (const gen_rt_real *)run->p;
    gen_rt_real *t = (gen_rt_real *)t_out, *x = (gen_rt_real *)x_out;
    gen_rt_real *lam = (gen_rt_real *)lam_out, *r = (gen_rt_real *)r_out;
    int k, e, n_ev = 0;
    ++n_calls;
    last_run = *run;
    if (run->x_op) last_x_op0 = (double)((const gen_rt_real *)run->x_op)[0];
    for (k = 0; k < run->rows; ++k) {
        double q, u;
        int stop = 0;
        if (p[1] == 1 && k == 3) {
            stats->n_out = k;
            stats->n_events = n_ev;
            stats->t_last = (double)t[k - 1];
            memcpy(stats->x_last, x + 2 * (k - 1), 2 * sizeof *x);
            return -3;
        }
        t[k] = (gen_rt_real)(k * run->dt);
        exact((double)x0[0], (double)x0[1], (double)p[0], (double)t[k], &q, &u);
        x[2 * k] = (gen_rt_real)q;
        x[2 * k + 1] = (gen_rt_real)u;
        lam[k] = (gen_rt_real)(2 * q);
        r[k] = (gen_rt_real)input_at(run, (double)t[k]);
        for (e = 0; k > 0 && e < run->n_events; ++e) {
            double lv = (double)((const gen_rt_real *)run->ev_level)[e];
            double a = (double)x[2 * (k - 1) + run->ev_which[e]] - lv;
            double b = (double)x[2 * k + run->ev_which[e]] - lv;
            int dir = run->ev_direction[e];
            if ((a < 0 && b >= 0 && dir >= 0) || (a > 0 && b <= 0 && dir <= 0)) {
                if (n_ev < run->capacity) {
                    run->log_which[n_ev] = e;
                    ((gen_rt_real *)run->log_t)[n_ev] = t[k];
                    memcpy((gen_rt_real *)run->log_x + 2 * n_ev, x + 2 * k, 2 * sizeof *x);
                }
                ++n_ev;
                if (run->ev_terminal[e]) stop = 1;
            }
        }
        if (stop) { ++k; break; }
    }
    stats->n_out = k;
    stats->n_events = n_ev;
    stats->t_last = (double)t[k - 1];
    memcpy(stats->x_last, x + 2 * (k - 1), 2 * sizeof *x);
    return 0;
}

static int constraints(double t, const void *xv, const void *p, void *fc)
{
    const gen_rt_real *x = (const gen_rt_real *)xv;
    if (((const gen_rt_real *)p)[1] == 2 && t > 0.15) return -5;
    ((gen_rt_real *)fc)[0] = x[0] + x[1];
    return 0;
}

static int energy(double t, const void *xv, const void *p, void *E)
{
    const gen_rt_real *x = (const gen_rt_real *)xv;
    (void)t;
    ((gen_rt_real *)E)[0] = (x[1] * x[1] + ((const gen_rt_real *)p)[0] * x[0] * x[0]) / 2;
    return 0;
}

static int auxiliary(double t, const void *xv, const void *r, const void *p, void *fa)
{
    (void)t; (void)r; (void)p;
    ((gen_rt_real *)fa)[0] = ((const gen_rt_real *)xv)[1];
    return 0;
}

static int outputs(double t, const void *xv, const void *rv, const void *p, void *y)
{
    const gen_rt_real r = ((const gen_rt_real *)rv)[0];
    (void)t; (void)p;
    if (r < 0) return -2;
    ((gen_rt_real *)y)[0] = ((const gen_rt_real *)xv)[0] * r;
    return 0;
}

static const char *message(int st)
{
    return st == -3 ? "fake step failure" : st == -5 ? "fake constraint failure" : "other";
}

static const gen_rt_main_model MODEL = {
    "osc", (int)sizeof(gen_rt_real), 1, 2, 1, 2, 1, 1, 2, 1, 1,
    x_names, r_names, p_names, y_names, a_names, i_names, p_default,
    opts_default, consistent, linearize, rows_of, simulate, constraints, energy, auxiliary,
    outputs, message, 0, 0, NULL, NULL, NULL};

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    CHECK(f != NULL);
    if (!f) return;
    fputs(text, f);
    fclose(f);
}


/* the first line of a CSV into header (hsize bytes), cut short when longer */
static void copy_header(char *header, size_t hsize, const char *line)
{
    size_t k = strlen(line);
    if (k >= hsize) k = hsize - 1;
    memcpy(header, line, k);
    header[k] = '\0';
}

/* a CSV written by the program: its header line and up to max_rows x 16 numbers */
static int read_back(const char *path, char *header, size_t hsize, double *v, int max_rows,
                     int *cols)
{
    char line[4096];
    int n = 0;
    FILE *f = fopen(path, "r");
    if (!f) return -1;
    if (!fgets(line, sizeof line, f)) { fclose(f); return -1; }
    line[strcspn(line, "\n")] = '\0';
    copy_header(header, hsize, line);
    while (n < max_rows && fgets(line, sizeof line, f)) {
        char *s = line, *end;
        int c = 0;
        for (;;) {
            double x = strtod(s, &end);
            if (end == s) break;
            v[n * 16 + c++] = x;
            if (*end != ',') break;
            s = end + 1;
        }
        *cols = c;
        ++n;
    }
    fclose(f);
    return n;
}

/* the events' CSV 'q,t,q,u' lines: t, q, u of each */
static int read_events(const char *path, char *header, size_t hsize, double *v, int max_rows)
{
    char line[512];
    int n = 0;
    FILE *f = fopen(path, "r");
    if (!f) return -1;
    if (!fgets(line, sizeof line, f)) { fclose(f); return -1; }
    line[strcspn(line, "\n")] = '\0';
    copy_header(header, hsize, line);
    while (n < max_rows && fgets(line, sizeof line, f))
        if (sscanf(line, "q,%lf,%lf,%lf", &v[16 * n], &v[16 * n + 1], &v[16 * n + 2]) == 3) ++n;
    fclose(f);
    return n;
}

static int run_main(int argc, const char *const *args)
{
    char *argv[32];
    int i;
    argv[0] = (char *)"osc_sim";
    for (i = 1; i < argc && i < 32; ++i) argv[i] = (char *)args[i - 1];
    return gen_rt_main(&MODEL, argc, argv);
}

#define RUN(...)                                                                   \
    do {                                                                           \
        static const char *const run_args_[] = {__VA_ARGS__};                      \
        code = run_main((int)(sizeof run_args_ / sizeof run_args_[0]) + 1, run_args_); \
    } while (0)

static void test_parse_real(void)
{
    double v = -1;
    CHECK_INT(gen_rt_main_parse_real(&MODEL, "0.25", &v), 0);
    CHECK(v == 0.25);
    CHECK_INT(gen_rt_main_parse_real(&MODEL, "0.1", &v), 0);
    CHECK(v == (double)(gen_rt_real)0.1);   /* rounded to the model's type */
    CHECK_INT(gen_rt_main_parse_real(&MODEL, "1e3", &v), 0);
    CHECK(v == 1000);
    CHECK_INT(gen_rt_main_parse_real(&MODEL, "", &v), -1);
    CHECK_INT(gen_rt_main_parse_real(&MODEL, "1x", &v), -1);
    CHECK_INT(gen_rt_main_parse_real(&MODEL, "nan", &v), -1);
    CHECK_INT(gen_rt_main_parse_real(&MODEL, "inf", &v), -1);
    CHECK_INT(gen_rt_main_parse_real(&MODEL, "1e999", &v), -1);
    CHECK_INT(gen_rt_main_parse_real(&MODEL, "1e39", &v), TEST_IS_FLOAT ? -1 : 0);
}

static void test_parse(void)
{
    gen_rt_main_args a;
    char *ok[] = {(char *)"osc_sim", (char *)"--t-end", (char *)"2.5", (char *)"--dt",
                  (char *)"0.125", (char *)"--x0", (char *)"u=3", (char *)"--x0", (char *)"q=-1",
                  (char *)"--param", (char *)"k=9", (char *)"--input", (char *)"F=0.5",
                  (char *)"--method", (char *)"rodas", (char *)"--rtol", (char *)"1e-6",
                  (char *)"--every", (char *)"4", (char *)"--no-project", (char *)"--event",
                  (char *)"u=0.5:down:terminal", (char *)"--event", (char *)"qF:both",
                  (char *)"--hold", (char *)"linear", (char *)"--x-op", (char *)"1,2",
                  (char *)"--no-consistent"};
    int n = (int)(sizeof ok / sizeof ok[0]);
    CHECK_INT(gen_rt_main_parse(&MODEL, n, ok, &a), GEN_RT_MAIN_CONTINUE);
    CHECK(a.t_end == 2.5 && a.dt == 0.125);
    CHECK(gen_rt_main_get(&MODEL, a.x, 0) == -1 && gen_rt_main_get(&MODEL, a.x, 1) == 3);
    CHECK(gen_rt_main_get(&MODEL, a.p, 0) == 9 && gen_rt_main_get(&MODEL, a.p, 1) == 0);
    CHECK(gen_rt_main_get(&MODEL, a.r, 0) == 0.5);
    CHECK(gen_rt_main_get(&MODEL, a.x_op, 0) == 1 && gen_rt_main_get(&MODEL, a.x_op, 1) == 2);
    CHECK_INT(a.opts.method, 2);
    CHECK(a.opts.rtol == (double)(gen_rt_real)1e-6 && a.opts.atol == 1e-10);
    CHECK_INT(a.opts.every, 4);
    CHECK_INT(a.opts.project, 0);
    CHECK_INT(a.consistent, 0);
    CHECK_INT(a.hold, 1);
    CHECK_INT(a.n_ev, 2);
    CHECK_INT(a.ev_which[0], 1);     /* u */
    CHECK_INT(a.ev_dir[0], -1);
    CHECK_INT(a.ev_term[0], 1);
    CHECK(gen_rt_main_get(&MODEL, a.ev_level, 0) == 0.5);
    CHECK_INT(a.ev_which[1], 2);     /* the output qF: NX + 0 */
    CHECK_INT(a.ev_dir[1], 0);
    CHECK_INT(a.ev_term[1], 0);
    gen_rt_main_free(&a);

    /* the defaults */
    CHECK_INT(gen_rt_main_parse(&MODEL, 1, ok, &a), GEN_RT_MAIN_CONTINUE);
    CHECK(a.t_end == 10 && a.dt == (double)((gen_rt_real)1 / 100));
    CHECK(gen_rt_main_get(&MODEL, a.p, 0) == 4);
    CHECK_INT(a.consistent, 1);
    CHECK_INT(a.opts.method, 0);
    CHECK(a.output == NULL && a.input_csv == NULL && a.n_ev == 0);
    gen_rt_main_free(&a);

    {   /* bad arguments: exit code 2 (a usage error), --help 0 */
        static const char *const bad[][3] = {
            {"--t-end", NULL, NULL}, {"--t-end", "-1", NULL}, {"--t-end", "x", NULL},
            {"--dt", "0", NULL}, {"--dt", "1e-400", NULL}, {"--rtol", "-1", NULL},
            {"--method", "euler", NULL}, {"--x0", "1", NULL}, {"--x0", "1,2,3", NULL},
            {"--x0", "v=1", NULL}, {"--x0", "q=abc", NULL}, {"--param", "m=1", NULL},
            {"--input", "F", NULL}, {"--hold", "cubic", NULL}, {"--period", "0", NULL},
            {"--every", "0", NULL}, {"--every", "2.5", NULL}, {"--x-op", "1,", NULL},
            {"--event", "q", NULL}, {"--event", "z:0", NULL}, {"--event", "q:2", NULL},
            {"--event", "q=nan:0", NULL}, {"--event", "q:0:final", NULL},
            {"--events-csv", "e.csv", NULL}, {"--bogus", NULL, NULL},
            {"--event", "q:0", "--event"}};
        size_t i;
        for (i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
            char *argv[4];
            int argc = 1;
            argv[0] = (char *)"osc_sim";
            while (argc < 4 && bad[i][argc - 1]) { argv[argc] = (char *)bad[i][argc - 1]; ++argc; }
            CHECK_INT(gen_rt_main_parse(&MODEL, argc, argv, &a), 2);
            gen_rt_main_free(&a);
        }
        {
            char *twice[] = {(char *)"osc_sim", (char *)"--event", (char *)"q:0",
                             (char *)"--event", (char *)"q=1:1"};
            char *help[] = {(char *)"osc_sim", (char *)"--x0", (char *)"q=1", (char *)"--help"};
            CHECK_INT(gen_rt_main_parse(&MODEL, 5, twice, &a), 2);
            gen_rt_main_free(&a);
            CHECK_INT(gen_rt_main_parse(&MODEL, 4, help, &a), 0);
            gen_rt_main_free(&a);
        }
    }
}

static void test_read_csv(void)
{
    void *d = NULL;
    int rows = 0, cols = 0;
    char header[64];
    write_file(IN_CSV, "# a comment\n\nt, F\n0,1\n0.5 2\r\n1\t-3\n");
    CHECK_INT(gen_rt_main_read_csv(&MODEL, IN_CSV, &d, &rows, &cols, header, sizeof header), 0);
    CHECK_INT(rows, 3);
    CHECK_INT(cols, 2);
    CHECK(strcmp(header, "t, F") == 0);
    if (d) {
        CHECK(gen_rt_main_get(&MODEL, d, 2) == 0.5 && gen_rt_main_get(&MODEL, d, 3) == 2);
        CHECK(gen_rt_main_get(&MODEL, d, 5) == -3);
    }
    free(d);
    d = NULL;
    /* without a header allowed, the header line is a malformed row */
    CHECK_INT(gen_rt_main_read_csv(&MODEL, IN_CSV, &d, &rows, &cols, NULL, 0), 2);
    write_file(IN_CSV, "1,2\n3\n");                   /* a short row */
    CHECK_INT(gen_rt_main_read_csv(&MODEL, IN_CSV, &d, &rows, &cols, NULL, 0), 2);
    write_file(IN_CSV, "1,2\n3,4,5\n");               /* a long row */
    CHECK_INT(gen_rt_main_read_csv(&MODEL, IN_CSV, &d, &rows, &cols, NULL, 0), 2);
    write_file(IN_CSV, "1,2\n3,x\n");                 /* not a number */
    CHECK_INT(gen_rt_main_read_csv(&MODEL, IN_CSV, &d, &rows, &cols, NULL, 0), 2);
    write_file(IN_CSV, "1,inf\n");                    /* not finite */
    CHECK_INT(gen_rt_main_read_csv(&MODEL, IN_CSV, &d, &rows, &cols, NULL, 0), 2);
    write_file(IN_CSV, "t,F\n# only a header\n");     /* no rows */
    CHECK_INT(gen_rt_main_read_csv(&MODEL, IN_CSV, &d, &rows, &cols, header, sizeof header), 2);
    CHECK_INT(gen_rt_main_read_csv(&MODEL, "no/such/file.csv", &d, &rows, &cols, NULL, 0), 1);
    CHECK(d == NULL);

    {   /* an input table: the columns by name, times strictly increasing */
        void *tt = NULL, *rt = NULL;
        int n = 0;
        write_file(IN_CSV, "F,t\n5,0\n6,0.25\n");
        CHECK_INT(gen_rt_main_read_inputs(&MODEL, IN_CSV, &tt, &rt, &n), 2);  /* t not first */
        write_file(IN_CSV, "t,F\n0,5\n0.25,6\n1,-7\n");
        CHECK_INT(gen_rt_main_read_inputs(&MODEL, IN_CSV, &tt, &rt, &n), 0);
        CHECK_INT(n, 3);
        if (tt && rt) {
            CHECK(gen_rt_main_get(&MODEL, tt, 1) == 0.25 && gen_rt_main_get(&MODEL, rt, 1) == 6);
            CHECK(gen_rt_main_get(&MODEL, tt, 2) == 1 && gen_rt_main_get(&MODEL, rt, 2) == -7);
        }
        free(tt); free(rt);
        tt = rt = NULL;
        write_file(IN_CSV, "t,G\n0,5\n");
        CHECK_INT(gen_rt_main_read_inputs(&MODEL, IN_CSV, &tt, &rt, &n), 2);  /* unknown input */
        write_file(IN_CSV, "t\n0\n");
        CHECK_INT(gen_rt_main_read_inputs(&MODEL, IN_CSV, &tt, &rt, &n), 2);  /* no column for F */
        write_file(IN_CSV, "0,5\n");
        CHECK_INT(gen_rt_main_read_inputs(&MODEL, IN_CSV, &tt, &rt, &n), 2);  /* no header */
        write_file(IN_CSV, "t,F\n0,5\n0,6\n");
        CHECK_INT(gen_rt_main_read_inputs(&MODEL, IN_CSV, &tt, &rt, &n), 2);  /* t not increasing */
        write_file(IN_CSV, "t,F\n0,5,1\n");
        CHECK_INT(gen_rt_main_read_inputs(&MODEL, IN_CSV, &tt, &rt, &n), 2);  /* header vs rows */
        CHECK(tt == NULL && rt == NULL);
    }
    remove(IN_CSV);
}

static void test_run(void)
{
    char header[256];
    static double v[64 * 16];
    int code, n, cols = 0, k;
    const double k_spring = 9, q0 = 0.5, u0 = -1;

    /* a run from a given state (no consistent state), every column checked */
    n_calls = 0;
    RUN("--t-end", "1", "--dt", "0.125", "--x0", "0.5,-1", "--param", "k=9", "--input", "F=2",
        "--no-consistent", "--method", "dopri5", "--output", OUT_CSV);
    CHECK_INT(code, 0);
    CHECK_INT(n_calls, 1);
    CHECK_INT(last_run.opts.method, 1);
    CHECK_INT(last_run.rows, 9);
    CHECK(last_run.K == NULL && last_run.n_table == 0 && last_run.n_events == 0);
    n = read_back(OUT_CSV, header, sizeof header, v, 64, &cols);
    CHECK_INT(n, 9);
    CHECK_INT(cols, 8);
    CHECK(strcmp(header, "t,q,u,lam0,fc0,energy,R,qF") == 0);
    for (k = 0; k < n && k < 9; ++k) {
        const double *row = v + 16 * k;
        gen_rt_real t = (gen_rt_real)(k * 0.125), q, u;
        double qd, ud;
        exact(q0, u0, k_spring, (double)t, &qd, &ud);
        q = (gen_rt_real)qd;
        u = (gen_rt_real)ud;
        CHECK(row[0] == (double)t);
        CHECK(row[1] == (double)q && row[2] == (double)u);
        CHECK(row[3] == (double)(gen_rt_real)(2 * qd));
        CHECK(row[4] == (double)(gen_rt_real)(q + u));
        CHECK(row[5] == (double)(gen_rt_real)((u * u + (gen_rt_real)k_spring * q * q) / 2));
        CHECK(row[6] == (double)u);
        CHECK(row[7] == (double)(gen_rt_real)(q * 2));
        CHECK_NEAR(row[5], 0.5 * (u0 * u0 + k_spring * q0 * q0), TOL(1e-14, 1e-5));
    }

    /* the consistent state (here: u0 + 1), --final-only passed on */
    RUN("--t-end", "0.5", "--dt", "0.25", "--x0", "q=1", "--final-only", "--output", OUT_CSV);
    CHECK_INT(code, 0);
    CHECK_INT(last_run.opts.final_only, 1);
    n = read_back(OUT_CSV, header, sizeof header, v, 64, &cols);
    CHECK_INT(n, 3);
    CHECK(v[0 * 16 + 1] == 1 && v[0 * 16 + 2] == 1);

    /* an input table: the inputs' columns appended; a negative input makes
     * the output nan (read back as a number: strtod reads "nan") */
    write_file(IN_CSV, "t,F\n0,1\n0.2,-1\n");
    RUN("--t-end", "0.5", "--dt", "0.125", "--x0", "1,0", "--no-consistent", "--input-csv", IN_CSV,
        "--output", OUT_CSV);
    CHECK_INT(code, 0);
    CHECK_INT(last_run.n_table, 2);
    n = read_back(OUT_CSV, header, sizeof header, v, 64, &cols);
    CHECK(strcmp(header, "t,q,u,lam0,fc0,energy,R,qF,F") == 0);
    CHECK_INT(n, 5);
    CHECK_INT(cols, 9);
    CHECK(v[1 * 16 + 8] == 1 && v[1 * 16 + 7] == v[1 * 16 + 1]);
    CHECK(v[2 * 16 + 8] == -1 && v[2 * 16 + 7] != v[2 * 16 + 7]);   /* t = 0.25: nan */

    /* the gain: its shape checked against NR x NS */
    write_file(IN_CSV, "1,2\n");
    RUN("--t-end", "0.25", "--gain", IN_CSV, "--x-op", "q=3", "--output", OUT_CSV);
    CHECK_INT(code, 0);
    CHECK(last_run.K != NULL && last_run.x_op != NULL);
    CHECK(last_x_op0 == 3);
    write_file(IN_CSV, "1,2,3\n");
    RUN("--t-end", "0.25", "--gain", IN_CSV, "--output", OUT_CSV);
    CHECK_INT(code, 2);

    /* a failing step: the rows before it, exit code 1 */
    RUN("--t-end", "1", "--dt", "0.125", "--param", "fail=1", "--output", OUT_CSV);
    CHECK_INT(code, 1);
    n = read_back(OUT_CSV, header, sizeof header, v, 64, &cols);
    CHECK_INT(n, 3);
    /* a failing constraint evaluation: the CSV truncated before that row */
    RUN("--t-end", "1", "--dt", "0.125", "--param", "fail=2", "--output", OUT_CSV);
    CHECK_INT(code, 1);
    n = read_back(OUT_CSV, header, sizeof header, v, 64, &cols);
    CHECK_INT(n, 2);

    /* output files that cannot be opened */
    RUN("--t-end", "0.25", "--output", "no/such/dir/out.csv");
    CHECK_INT(code, 1);
    RUN("--t-end", "0.25", "--event", "q:0", "--events-csv", "no/such/dir/ev.csv", "--output", OUT_CSV);
    CHECK_INT(code, 1);
    RUN("--t-end", "0.25", "--input-csv", "no/such/in.csv");
    CHECK_INT(code, 1);
    RUN("--t-end", "1e300", "--dt", "1e-300");    /* too many rows */
    CHECK_INT(code, 2);
    remove(IN_CSV);
}

static void test_events(void)
{
    char header[256];
    static double v[64 * 16];
    int code, n, cols = 0, k;
    /* k = 4: q = cos(2 t) crosses 0 downwards at pi/4 (between rows 7 and
     * 8 of dt = 0.1), upwards at 3 pi/4 (rows 23, 24) */
    n_calls = 0;
    RUN("--t-end", "3", "--dt", "0.1", "--x0", "1,0", "--no-consistent", "--event", "q:0",
        "--output", OUT_CSV, "--events-csv", EV_CSV);
    CHECK_INT(code, 0);
    CHECK_INT(n_calls, 1);
    CHECK_INT(last_run.capacity, GEN_RT_MAIN_EVENT_LOG);
    n = read_events(EV_CSV, header, sizeof header, v, 64);
    CHECK(strcmp(header, "event,t,q,u") == 0);
    CHECK_INT(n, 2);
    CHECK_NEAR(v[0 * 16 + 0], 0.8, 1e-6);      /* the first row after the crossing */
    CHECK_NEAR(v[1 * 16 + 0], 2.4, 1e-6);
    CHECK(v[0 * 16 + 1] < 0 && v[1 * 16 + 1] > 0);

    /* terminal: the run ends at the event's row */
    RUN("--t-end", "3", "--dt", "0.1", "--x0", "1,0", "--no-consistent", "--event", "q:down:terminal",
        "--output", OUT_CSV);
    CHECK_INT(code, 0);
    n = read_back(OUT_CSV, header, sizeof header, v, 64, &cols);
    CHECK_INT(n, 9);
    CHECK_NEAR(v[8 * 16 + 0], 0.8, 1e-6);

    /* more events than the log holds: the run again with room for all;
     * k = 3600 * pi^2 (w = 60 pi): 2 crossings of u = 0 per 1/30 */
    n_calls = 0;
    RUN("--t-end", "20", "--dt", "0.001", "--x0", "1,0.001", "--no-consistent",
        "--param", "k=35530.575843921691", "--event", "u:both", "--final-only",
        "--output", OUT_CSV, "--events-csv", EV_CSV);
    CHECK_INT(code, 0);
    CHECK_INT(n_calls, 2);
    CHECK(last_run.capacity > GEN_RT_MAIN_EVENT_LOG);
    {
        FILE *f = fopen(EV_CSV, "r");
        char line[256];
        int lines = 0;
        while (f && fgets(line, sizeof line, f)) ++lines;
        if (f) fclose(f);
        CHECK_INT(lines - 1, last_run.capacity);
        CHECK_NEAR(lines - 1, 1200, 2);
    }
    for (k = 0; k < 1; ++k) remove(EV_CSV);
    remove(OUT_CSV);
}

int main(void)
{
    test_parse_real();
    test_parse();
    test_read_csv();
    test_run();
    test_events();
    TEST_END();
}
