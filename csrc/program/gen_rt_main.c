/*
 * gen_rt_main.c - the standalone simulator of a generated model (see
 * gen_rt_main.h): the command line, the input tables, the run loop and the
 * CSV. The model is reached only through its gen_rt_main_model.
 */
#include "gen_rt_main.h"
/* the method and hold names with their codes (GEN_RT_METHOD_NAMES,
 * GEN_RT_HOLD_NAMES in gen_rt_abi.h, rendered from gen/codegen/abi.py; every model
 * checks at compile time that its codes are these) */
#include "gen_rt.h"

#include <errno.h>
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* the names a command line may give and their codes, from gen_rt_abi.h */
#define GEN_RT_MAIN_NAME_(name, code) name,
#define GEN_RT_MAIN_CODE_(name, code) code,
static const char *const method_names[] = { GEN_RT_METHOD_NAMES(GEN_RT_MAIN_NAME_) };
static const int method_codes[] = { GEN_RT_METHOD_NAMES(GEN_RT_MAIN_CODE_) };
static const char *const hold_names[] = { GEN_RT_HOLD_NAMES(GEN_RT_MAIN_NAME_) };
static const int hold_codes[] = { GEN_RT_HOLD_NAMES(GEN_RT_MAIN_CODE_) };
#undef GEN_RT_MAIN_NAME_
#undef GEN_RT_MAIN_CODE_

/* the code of name v in names (n of them), -1 if it is none of them */
static int name_code(const char *v, const char *const *names, const int *codes, int n)
{
    int i;
    for (i = 0; i < n; ++i)
        if (strcmp(v, names[i]) == 0) return codes[i];
    return -1;
}

/* ------------------------------------------------------------ scalars */
double gen_rt_main_get(const gen_rt_main_model *m, const void *a, long i)
{
    if (m->real_size == (int)sizeof(float)) return (double)((const float *)a)[i];
    return ((const double *)a)[i];
}

void gen_rt_main_set(const gen_rt_main_model *m, void *a, long i, double v)
{
    if (m->real_size == (int)sizeof(float)) ((float *)a)[i] = (float)v;
    else ((double *)a)[i] = v;
}

/* the address of element i */
static void *at(const gen_rt_main_model *m, void *a, long i)
{
    return (char *)a + i * (long)m->real_size;
}

static const void *cat(const gen_rt_main_model *m, const void *a, long i)
{
    return (const char *)a + i * (long)m->real_size;
}

/* n reals (at least one: C has no empty arrays), zero */
static void *reals(const gen_rt_main_model *m, long n)
{
    return calloc((size_t)(n > 0 ? n : 1), (size_t)m->real_size);
}

/* parsing in double; a value the model's scalar type cannot hold is an error */
int gen_rt_main_parse_real(const gen_rt_main_model *m, const char *s, double *out)
{
    const int is_float = m->real_size == (int)sizeof(float);
    const double real_max = is_float ? (double)FLT_MAX : DBL_MAX;
    char *end = NULL;
    double v;
    errno = 0;
    v = strtod(s, &end);
    if (end == s || *end != '\0' || errno == ERANGE) return -1;
    if (!(v == v) || v > real_max || v < -real_max) return -1;
    *out = is_float ? (double)(float)v : v;
    return 0;
}

static int parse_into(const gen_rt_main_model *m, const char *s, void *a, long i)
{
    double v;
    if (gen_rt_main_parse_real(m, s, &v)) return -1;
    gen_rt_main_set(m, a, i, v);
    return 0;
}

/* -------------------------------------------------------- messages */
static void usage(const gen_rt_main_model *m, FILE *out)
{
    int i;
    fprintf(out,
        "Usage: %s_sim [options]\n"
        "Simulate the model '%s' and write a CSV (t, states, multipliers,\n"
        "constraint residuals) to stdout or --output.\n\n", m->name, m->name);
    fprintf(out,
        "  --t-end T          end time (default 10)\n"
        "  --dt DT            output interval; also the RK4 step (default 0.01)\n"
        "  --method M         rk4 (default), dopri5 or rodas4 (alias rodas: implicit, for\n"
        "                     stiff models)\n"
        "  --rtol R --atol A  dopri5/rodas4 tolerances (default 1e-8, 1e-10)\n"
        "  --x0 NAME=V        initial value of a state (repeatable), or\n"
        "  --x0 V1,V2,...     all %d states in order\n", m->nx);
    fprintf(out,
        "  --param NAME=V     constant value (repeatable)\n"
        "  --input NAME=V     constant input value (repeatable); with --gain: r_op\n"
        "  --input-csv FILE   inputs from a table: a header 't,<input names>' then rows\n"
        "  --hold H           the table between rows: zoh (default) or linear\n"
        "  --gain FILE        linear feedback r = r_op - K (x_ind - x_op_ind): K as NR rows\n"
        "                     of NS comma-separated numbers (on the independent state)\n"
        "  --x-op NAME=V      operating state of the gain (repeatable), or V1,V2,...\n"
        "  --period TS        sample the feedback every TS and hold it (default: continuous)\n"
        "  --every K          write every K-th output row and the last\n"
        "  --final-only       write only the row at --t-end\n"
        "  --event NAME[=LEVEL]:DIR[:terminal]\n"
        "                     log the crossings of LEVEL (default 0) by a state or an output\n"
        "                     NAME; DIR +1 (or 1, up), -1 (down) or 0 (both); terminal: the\n"
        "                     first crossing ends the run, its state the last row (repeatable)\n"
        "  --events-csv FILE  write the events to FILE as CSV 'event,t,<states>' (default:\n"
        "                     one line 'event NAME t=T <state>' per event on stderr)\n"
        "  --no-consistent    do not solve the dependent states from the independent ones\n"
        "  --no-project       do not project onto the constraints after each step\n"
        "  --output FILE      write the CSV to FILE\n"
        "  --linearize        print A and B at the (consistent) initial state and exit\n"
        "  --help             this text\n\n"
        "States:");
    for (i = 0; i < m->nx; ++i) fprintf(out, " %s", m->state_names[i]);
    if (m->ny) {
        fprintf(out, "\nOutputs:");
        for (i = 0; i < m->ny; ++i) fprintf(out, " %s", m->output_names[i]);
    }
    if (m->np) {
        fprintf(out, "\nConstants:");
        for (i = 0; i < m->np; ++i) fprintf(out, " %s", m->param_names[i]);
    }
    if (m->nr) {
        fprintf(out, "\nInputs:");
        for (i = 0; i < m->nr; ++i) fprintf(out, " %s", m->input_names[i]);
    }
    fprintf(out, "\n");
}

static int fail_usage(const gen_rt_main_model *m, const char *msg, const char *arg)
{
    fprintf(stderr, "%s_sim: %s%s%s\n", m->name, msg, arg ? ": " : "", arg ? arg : "");
    fprintf(stderr, "Try '%s_sim --help'.\n", m->name);
    return 2;
}

/* --------------------------------------------------------- arguments */
static int find_name(const char *const *names, int n, const char *name, size_t len)
{
    int i;
    for (i = 0; i < n; ++i)
        if (strlen(names[i]) == len && strncmp(names[i], name, len) == 0) return i;
    return -1;
}

/* NAME=V into vals[] by name; returns 0 or a usage error code */
static int assign(const gen_rt_main_model *m, const char *arg, const char *const *names, int n,
                  void *vals, const char *what)
{
    const char *eq = strchr(arg, '=');
    int k;
    if (!eq) return fail_usage(m, "expected NAME=VALUE", arg);
    k = find_name(names, n, arg, (size_t)(eq - arg));
    if (k < 0) {
        fprintf(stderr, "%s_sim: unknown %s name in '%s'\n", m->name, what, arg);
        return 2;
    }
    if (parse_into(m, eq + 1, vals, k)) return fail_usage(m, "not a finite number", arg);
    return 0;
}

/* a list V1,V2,... of exactly n numbers into vals[]; returns 0 or a usage error */
static int parse_list(const gen_rt_main_model *m, const char *v, void *vals, int n,
                      const char *what)
{
    char buf[4096];
    char *tok;
    int k = 0;
    if (strlen(v) >= sizeof buf) return fail_usage(m, "list too long", what);
    strcpy(buf, v);
    for (tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
        if (k >= n) return fail_usage(m, "too many values", what);
        if (parse_into(m, tok, vals, k)) return fail_usage(m, "not a finite number", tok);
        ++k;
    }
    if (k != n) return fail_usage(m, "the list needs one value per state", what);
    return 0;
}

/* --x0 V1,V2,...: all states in order */
static int parse_x0_list(const gen_rt_main_model *m, const char *v, void *x)
{
    char buf[4096];
    char *tok;
    int n = 0;
    if (strlen(v) >= sizeof buf) return fail_usage(m, "--x0 list too long", NULL);
    strcpy(buf, v);
    for (tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
        if (n >= m->nx) return fail_usage(m, "--x0 has more values than states", v);
        if (parse_into(m, tok, x, n)) return fail_usage(m, "not a finite number", tok);
        ++n;
    }
    if (n != m->nx) return fail_usage(m, "--x0 list needs one value per state", v);
    return 0;
}

/* the states and outputs an event may watch, for an error message */
static void list_event_names(const gen_rt_main_model *m, FILE *out)
{
    int i;
    fprintf(out, "states:");
    for (i = 0; i < m->nx; ++i) fprintf(out, " %s", m->state_names[i]);
    if (m->ny) {
        fprintf(out, "; outputs:");
        for (i = 0; i < m->ny; ++i) fprintf(out, " %s", m->output_names[i]);
    } else {
        fprintf(out, " (the model has no outputs)");
    }
    fprintf(out, "\n");
}

/* the NAME of a state, or of an output (NX + its index) */
static const char *event_name(const gen_rt_main_model *m, int which)
{
    return which < m->nx ? m->state_names[which] : m->output_names[which - m->nx];
}

/* --event NAME[=LEVEL]:DIR[:terminal] into which (0..NX-1 a state, NX.. an
 * output), direction, terminal and level; 0 or a usage error code */
static int parse_event(const gen_rt_main_model *m, const char *arg, int *which, int *direction,
                       int *terminal, double *level)
{
    char buf[512];
    char *colon, *dir, *flag, *eq;
    size_t len;
    if (strlen(arg) >= sizeof buf) return fail_usage(m, "--event too long", NULL);
    strcpy(buf, arg);
    colon = strchr(buf, ':');
    if (!colon) return fail_usage(m, "--event must be NAME[=LEVEL]:DIR[:terminal]", arg);
    *colon = '\0';
    dir = colon + 1;
    flag = strchr(dir, ':');
    if (flag) *flag++ = '\0';
    *level = 0;
    eq = strchr(buf, '=');
    if (eq) {
        *eq = '\0';
        if (gen_rt_main_parse_real(m, eq + 1, level))
            return fail_usage(m, "--event: the level is not a finite number", arg);
    }
    len = strlen(buf);
    *which = find_name(m->state_names, m->nx, buf, len);
    if (*which < 0 && m->ny) {
        *which = find_name(m->output_names, m->ny, buf, len);
        if (*which >= 0) *which += m->nx;
    }
    if (*which < 0) {
        fprintf(stderr, "%s_sim: --event: unknown state or output '%s' in '%s'; ", m->name, buf,
                arg);
        list_event_names(m, stderr);
        return 2;
    }
    if (strcmp(dir, "+1") == 0 || strcmp(dir, "1") == 0 || strcmp(dir, "up") == 0) *direction = 1;
    else if (strcmp(dir, "-1") == 0 || strcmp(dir, "down") == 0) *direction = -1;
    else if (strcmp(dir, "0") == 0 || strcmp(dir, "both") == 0) *direction = 0;
    else return fail_usage(m, "--event: the direction must be +1 (1, up), -1 (down) or 0 (both)",
                           arg);
    *terminal = 0;
    if (flag) {
        if (strcmp(flag, "terminal") != 0)
            return fail_usage(m, "--event: expected ':terminal' after the direction", arg);
        *terminal = 1;
    }
    return 0;
}

void gen_rt_main_free(gen_rt_main_args *a)
{
    free(a->x); free(a->x_op); free(a->p); free(a->r); free(a->ev_level);
    a->x = a->x_op = a->p = a->r = a->ev_level = NULL;
}

/* the options that take a value */
static int needs_value(const char *a)
{
    static const char *const with_value[] = {
        "--t-end", "--dt", "--method", "--rtol", "--atol", "--x0", "--param", "--input",
        "--output", "--input-csv", "--hold", "--gain", "--x-op", "--period", "--every",
        "--event", "--events-csv"};
    size_t i;
    for (i = 0; i < sizeof with_value / sizeof with_value[0]; ++i)
        if (strcmp(a, with_value[i]) == 0) return 1;
    return 0;
}

int gen_rt_main_parse(const gen_rt_main_model *m, int argc, char **argv, gen_rt_main_args *a)
{
    int i, k, st;
    long j;
    memset(a, 0, sizeof *a);
    a->t_end = 10;
    a->dt = m->real_size == (int)sizeof(float) ? (double)((float)1 / 100) : (double)1 / 100;
    a->consistent = 1;
    a->hold = GEN_RT_HOLD_ZOH;
    a->x = reals(m, m->nx);
    a->x_op = reals(m, m->nx);
    a->p = reals(m, m->np);
    a->r = reals(m, m->nr);
    a->ev_level = reals(m, GEN_RT_MAIN_MAX_EVENTS);
    if (!a->x || !a->x_op || !a->p || !a->r || !a->ev_level) {
        fprintf(stderr, "%s_sim: out of memory\n", m->name);
        return 1;
    }
    if (m->np) memcpy(a->p, m->p_default, (size_t)m->np * (size_t)m->real_size);
    m->options_default(&a->opts);

    for (i = 1; i < argc; ++i) {
        const char *arg = argv[i];
        const char *v = (i + 1 < argc) ? argv[i + 1] : NULL;
        if (needs_value(arg) && !v) return fail_usage(m, "missing value after", arg);
        if (!v) v = "";   /* the last option, which takes no value */
        if (strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0) { usage(m, stdout); return 0; }
        else if (strcmp(arg, "--t-end") == 0) {
            if (gen_rt_main_parse_real(m, v, &a->t_end)) return fail_usage(m, "--t-end needs a number", v);
            ++i;
        } else if (strcmp(arg, "--dt") == 0) {
            if (gen_rt_main_parse_real(m, v, &a->dt) || !(a->dt > 0))
                return fail_usage(m, "--dt needs a positive number", v);
            ++i;
        } else if (strcmp(arg, "--rtol") == 0) {
            if (gen_rt_main_parse_real(m, v, &a->opts.rtol) || !(a->opts.rtol > 0))
                return fail_usage(m, "--rtol needs a positive number", v);
            ++i;
        } else if (strcmp(arg, "--atol") == 0) {
            if (gen_rt_main_parse_real(m, v, &a->opts.atol) || !(a->opts.atol > 0))
                return fail_usage(m, "--atol needs a positive number", v);
            ++i;
        } else if (strcmp(arg, "--method") == 0) {
            if ((a->opts.method = name_code(v, method_names, method_codes,
                                            (int)(sizeof method_codes / sizeof *method_codes))) < 0)
                return fail_usage(m, "--method must be rk4, dopri5 or rodas4", v);
            ++i;
        } else if (strcmp(arg, "--x0") == 0) {
            if (strchr(v, '=')) {
                if ((st = assign(m, v, m->state_names, m->nx, a->x, "state"))) return st;
            } else if ((st = parse_x0_list(m, v, a->x))) {
                return st;
            }
            ++i;
        } else if (strcmp(arg, "--param") == 0) {
            if (!m->np) return fail_usage(m, "this model has no constants", v);
            if ((st = assign(m, v, m->param_names, m->np, a->p, "constant"))) return st;
            ++i;
        } else if (strcmp(arg, "--input") == 0) {
            if (!m->nr) return fail_usage(m, "this model has no inputs", v);
            if ((st = assign(m, v, m->input_names, m->nr, a->r, "input"))) return st;
            ++i;
        } else if (strcmp(arg, "--input-csv") == 0) { a->input_csv = v; ++i; }
        else if (strcmp(arg, "--gain") == 0) { a->gain_file = v; ++i; }
        else if (strcmp(arg, "--hold") == 0) {
            if ((a->hold = name_code(v, hold_names, hold_codes,
                                     (int)(sizeof hold_codes / sizeof *hold_codes))) < 0)
                return fail_usage(m, "--hold must be zoh or linear", v);
            ++i;
        } else if (strcmp(arg, "--period") == 0) {
            if (gen_rt_main_parse_real(m, v, &a->period) || !(a->period > 0))
                return fail_usage(m, "--period needs a positive number", v);
            ++i;
        } else if (strcmp(arg, "--x-op") == 0) {
            if (strchr(v, '=')) {
                if ((st = assign(m, v, m->state_names, m->nx, a->x_op, "state"))) return st;
            } else if ((st = parse_list(m, v, a->x_op, m->nx, "--x-op"))) {
                return st;
            }
            ++i;
        } else if (strcmp(arg, "--every") == 0) {
            char *end = NULL;
            j = strtol(v, &end, 10);
            if (end == v || *end != '\0' || j < 1 || j > 1000000000L)
                return fail_usage(m, "--every needs a positive integer", v);
            a->opts.every = (int)j;
            ++i;
        } else if (strcmp(arg, "--event") == 0) {
            double level;
            int n = a->n_ev;
            if (n >= GEN_RT_MAIN_MAX_EVENTS) return fail_usage(m, "too many --event options", v);
            if ((st = parse_event(m, v, &a->ev_which[n], &a->ev_dir[n], &a->ev_term[n], &level)))
                return st;
            gen_rt_main_set(m, a->ev_level, n, level);
            for (k = 0; k < n; ++k)
                if (a->ev_which[k] == a->ev_which[n])
                    return fail_usage(m, "--event: that state or output has an event already", v);
            ++a->n_ev;
            ++i;
        } else if (strcmp(arg, "--events-csv") == 0) { a->events_csv = v; ++i; }
        else if (strcmp(arg, "--final-only") == 0) a->opts.final_only = 1;
        else if (strcmp(arg, "--output") == 0) { a->output = v; ++i; }
        else if (strcmp(arg, "--no-consistent") == 0) a->consistent = 0;
        else if (strcmp(arg, "--no-project") == 0) a->opts.project = 0;
        else if (strcmp(arg, "--linearize") == 0) a->linearize = 1;
        else return fail_usage(m, "unknown option", arg);
    }
    if (!(a->t_end >= 0)) return fail_usage(m, "--t-end must be >= 0", NULL);
    if (a->events_csv && a->n_ev == 0 && m->nh == 0)
        return fail_usage(m, "--events-csv needs at least one --event", a->events_csv);
    return GEN_RT_MAIN_CONTINUE;
}

/* ----------------------------------------------------------- tables */
int gen_rt_main_read_csv(const gen_rt_main_model *m, const char *path, void **data, int *rows,
                         int *cols, char *header, size_t header_size)
{
    char line[65536];
    FILE *f = fopen(path, "r");
    int cap = 0, n = 0, c0 = -1, lineno = 0;
    void *d = NULL;
    if (header) header[0] = '\0';
    if (!f) {
        fprintf(stderr, "%s_sim: cannot open %s: %s\n", m->name, path, strerror(errno));
        return 1;
    }
    while (fgets(line, sizeof line, f)) {
        char *tok, *nl = strpbrk(line, "\r\n");
        int c = 0;
        ++lineno;
        if (nl) *nl = '\0';
        if (line[0] == '\0' || line[0] == '#') continue;
        if (n == 0 && c0 < 0 && header && header[0] == '\0') {
            char *end;
            (void)strtod(line, &end);
            if (end == line) {   /* not a number: the header */
                size_t len = strlen(line);
                if (len >= header_size) len = header_size - 1;
                memcpy(header, line, len);
                header[len] = '\0';
                continue;
            }
        }
        for (tok = strtok(line, ", \t"); tok; tok = strtok(NULL, ", \t")) {
            long idx = (long)n * (c0 > 0 ? c0 : 1) + c;
            if (idx >= cap) {
                void *nd;
                cap = cap ? 2 * cap : 256;
                nd = realloc(d, (size_t)cap * (size_t)m->real_size);
                if (!nd) {
                    free(d); fclose(f);
                    fprintf(stderr, "%s_sim: out of memory\n", m->name);
                    return 1;
                }
                d = nd;
            }
            if (parse_into(m, tok, d, idx)) {
                fprintf(stderr, "%s_sim: %s:%d: not a finite number: %s\n", m->name, path, lineno,
                        tok);
                free(d); fclose(f);
                return 2;
            }
            ++c;
            if (c0 > 0 && c > c0) break;
        }
        if (c0 < 0) c0 = c;
        if (c != c0 || c == 0) {
            fprintf(stderr, "%s_sim: %s:%d: expected %d values, got %d\n", m->name, path, lineno,
                    c0, c);
            free(d); fclose(f);
            return 2;
        }
        ++n;
    }
    fclose(f);
    if (n == 0) {
        fprintf(stderr, "%s_sim: %s holds no rows of numbers\n", m->name, path);
        free(d);
        return 2;
    }
    *data = d; *rows = n; *cols = c0;
    return 0;
}

int gen_rt_main_read_inputs(const gen_rt_main_model *m, const char *path, void **t_table,
                            void **r_table, int *n_rows)
{
    char header[4096];
    int n, c, i, k = 0, st, *col;
    char *tok;
    void *table = NULL, *tt, *rt;
    const int nr = m->nr;
    if ((st = gen_rt_main_read_csv(m, path, &table, &n, &c, header, sizeof header))) return st;
    if (header[0] == '\0') {
        free(table);
        return fail_usage(m, "the input table needs a header line 't,<input names>'", path);
    }
    col = (int *)malloc((size_t)nr * sizeof *col);
    if (!col) { free(table); fprintf(stderr, "%s_sim: out of memory\n", m->name); return 1; }
    for (i = 0; i < nr; ++i) col[i] = -1;
    for (tok = strtok(header, ", \t"); tok; tok = strtok(NULL, ", \t"), ++k) {
        int j;
        if (k == 0) {
            if (strcmp(tok, "t") != 0) {
                free(table); free(col);
                return fail_usage(m, "the input table's first column must be t", path);
            }
            continue;
        }
        j = find_name(m->input_names, nr, tok, strlen(tok));
        if (j < 0) {
            free(table); free(col);
            fprintf(stderr, "%s_sim: %s: unknown input '%s'\n", m->name, path, tok);
            return 2;
        }
        col[j] = k;
    }
    if (k != c) {
        free(table); free(col);
        return fail_usage(m, "the input table's header and rows differ in length", path);
    }
    for (i = 0; i < nr; ++i)
        if (col[i] < 0) {
            free(table); free(col);
            fprintf(stderr, "%s_sim: %s: no column for input '%s'\n", m->name, path,
                    m->input_names[i]);
            return 2;
        }
    tt = malloc((size_t)n * (size_t)m->real_size);
    rt = malloc((size_t)n * (size_t)nr * (size_t)m->real_size);
    if (!tt || !rt) {
        free(table); free(col); free(tt); free(rt);
        fprintf(stderr, "%s_sim: out of memory\n", m->name);
        return 1;
    }
    for (k = 0; k < n; ++k) {
        gen_rt_main_set(m, tt, k, gen_rt_main_get(m, table, (long)k * c));
        for (i = 0; i < nr; ++i)
            gen_rt_main_set(m, rt, (long)k * nr + i, gen_rt_main_get(m, table, (long)k * c + col[i]));
        if (k > 0 && !(gen_rt_main_get(m, tt, k) > gen_rt_main_get(m, tt, k - 1))) {
            free(table); free(col); free(tt); free(rt);
            return fail_usage(m, "the input table's times must be strictly increasing", path);
        }
    }
    free(table); free(col);
    *t_table = tt; *r_table = rt; *n_rows = n;
    return 0;
}

/* ----------------------------------------------------------- output */
static void print_matrix(const gen_rt_main_model *m, FILE *out, const char *label,
                         const void *a, int rows, int cols)
{
    int i, j;
    fprintf(out, "%s (%d x %d)\n", label, rows, cols);
    for (i = 0; i < rows; ++i) {
        fprintf(out, "  %-10s", m->ind_names[i]);
        for (j = 0; j < cols; ++j)   /* + 0: no -0 */
            fprintf(out, " % .12g", gen_rt_main_get(m, a, (long)i * cols + j) + 0);
        fprintf(out, "\n");
    }
}

/* --linearize: A and B at the (consistent) initial state */
static int run_linearize(const gen_rt_main_model *m, const gen_rt_main_args *a)
{
    void *A = reals(m, (long)m->ns * m->ns), *B = reals(m, (long)m->ns * m->nr);
    int i, st;
    if (!A || !B) {
        free(A); free(B);
        fprintf(stderr, "%s_sim: out of memory\n", m->name);
        return 1;
    }
    st = m->linearize(a->x, a->r, a->p, A, B);
    if (st) {
        fprintf(stderr, "%s_sim: linearize failed: %s\n", m->name, m->status_message(st));
        free(A); free(B);
        return 1;
    }
    printf("state:");
    for (i = 0; i < m->nx; ++i) printf(" %s=%.12g", m->state_names[i], gen_rt_main_get(m, a->x, i) + 0);
    printf("\n");
    print_matrix(m, stdout, "A", A, m->ns, m->ns);
    print_matrix(m, stdout, "B", B, m->ns, m->nr);
    free(A); free(B);
    return 0;
}

static void write_header(const gen_rt_main_model *m, FILE *out, int varying)
{
    int i;
    fprintf(out, "t");
    for (i = 0; i < m->nx; ++i) fprintf(out, ",%s", m->state_names[i]);
    for (i = 0; i < m->mv; ++i) fprintf(out, ",lam%d", i);
    for (i = 0; i < m->mc; ++i) fprintf(out, ",fc%d", i);
    if (m->eval_energy) fprintf(out, ",energy");
    for (i = 0; i < m->na; ++i) fprintf(out, ",%s", m->aux_names[i]);   /* reaction forces */
    for (i = 0; i < m->ny; ++i) fprintf(out, ",%s", m->output_names[i]);
    if (varying)   /* varying inputs: the inputs in effect from each row on */
        for (i = 0; i < m->nr; ++i) fprintf(out, ",%s", m->input_names[i]);
    fprintf(out, "\n");
}

/* n values of a column group, or nan for each when its evaluation failed */
static void write_values(const gen_rt_main_model *m, FILE *out, int st, const void *v, int n)
{
    int i;
    for (i = 0; i < n; ++i) {
        if (st == 0) fprintf(out, ",%.17g", gen_rt_main_get(m, v, i));
        else fprintf(out, ",nan");
    }
}

/* the rows of a run: 0, or 1 when an evaluation failed (the CSV truncated) */
static int write_rows(const gen_rt_main_model *m, const gen_rt_main_args *a, FILE *out,
                      int written, int varying, const void *t_out, const void *x_out,
                      const void *l_out, const void *r_out, void *work)
{
    const long smv = m->mv > 0 ? m->mv : 1, snr = m->nr > 0 ? m->nr : 1;
    long mc = m->mc > 0 ? m->mc : 1, na = m->na > 0 ? m->na : 1;
    void *fc = work, *E = at(m, work, mc), *fa = at(m, work, mc + 1);
    void *y = at(m, work, mc + 1 + na);
    int k, i, st;
    for (k = 0; k < written; ++k) {
        double t = gen_rt_main_get(m, t_out, k);
        const void *xk = cat(m, x_out, (long)k * m->nx), *rk = cat(m, r_out, (long)k * snr);
        st = m->eval_constraints(t, xk, a->p, fc);
        if (st) {
            fprintf(stderr, "%s_sim: evaluation failed at t=%.17g: %s; CSV truncated after %d rows\n",
                    m->name, t, m->status_message(st), k);
            return 1;
        }
        fprintf(out, "%.17g", t);
        for (i = 0; i < m->nx; ++i) fprintf(out, ",%.17g", gen_rt_main_get(m, xk, i));
        for (i = 0; i < m->mv; ++i) fprintf(out, ",%.17g", gen_rt_main_get(m, l_out, (long)k * smv + i));
        for (i = 0; i < m->mc; ++i) fprintf(out, ",%.17g", gen_rt_main_get(m, fc, i));
        if (m->eval_energy) write_values(m, out, m->eval_energy(t, xk, a->p, E), E, 1);
        if (m->na) write_values(m, out, m->eval_auxiliary(t, xk, rk, a->p, fa), fa, m->na);
        if (m->ny) write_values(m, out, m->eval_outputs(t, xk, rk, a->p, y), y, m->ny);
        if (varying)
            for (i = 0; i < m->nr; ++i) fprintf(out, ",%.17g", gen_rt_main_get(m, rk, i));
        fprintf(out, "\n");
    }
    return 0;
}

/* the events of a run: to ev_out as CSV, else one line each on stderr */
static void write_events(const gen_rt_main_model *m, const gen_rt_main_args *a, FILE *ev_out,
                         int n_log, const int *log_which, const void *log_t, const void *log_x,
                         const void *log_x_after)
{
    int k, i;
    if (ev_out) {
        fprintf(ev_out, "event,t");
        for (i = 0; i < m->nx; ++i) fprintf(ev_out, ",%s", m->state_names[i]);
        /* a hybrid model: the state after each event too (a jump's) */
        if (m->nh > 0)
            for (i = 0; i < m->nx; ++i) fprintf(ev_out, ",%s_after", m->state_names[i]);
        fprintf(ev_out, "\n");
    }
    for (k = 0; k < n_log; ++k) {
        FILE *f = ev_out ? ev_out : stderr;
        const char *sep = ev_out ? "," : " t=";
        int w = log_which[k];
        /* hybrid jumps are the log's entries n_ev + j (declaration j),
         * n_ev + nh + j (lift-off of contact j) and n_ev + 2 nh + j
         * (contact j held from then on) */
        const char *suffix = w >= a->n_ev + GEN_RT_HYBRID_LOG_HOLD * m->nh ? ".hold"
                             : w >= a->n_ev + m->nh ? ".liftoff" : "";
        const char *name = w < a->n_ev ? event_name(m, a->ev_which[w])
                         : m->hybrid_names[(w - a->n_ev) % (m->nh > 0 ? m->nh : 1)];
        fprintf(f, "%s%s%s%s%.17g", ev_out ? "" : "event ", name, suffix, sep,
                gen_rt_main_get(m, log_t, k));
        for (i = 0; i < m->nx; ++i) {
            double v = gen_rt_main_get(m, log_x, (long)k * m->nx + i);
            if (ev_out) fprintf(f, ",%.17g", v);
            else fprintf(f, " %s=%.17g", m->state_names[i], v);
        }
        if (m->nh > 0 && log_x_after)
            for (i = 0; i < m->nx; ++i) {
                double v = gen_rt_main_get(m, log_x_after, (long)k * m->nx + i);
                if (ev_out) fprintf(f, ",%.17g", v);
                else fprintf(f, " %s_after=%.17g", m->state_names[i], v);
            }
        fprintf(f, "\n");
    }
}

/* a run that a hybrid declaration stopped (its log's last entry k: the
 * start refused, or a jump whose map is not finite or violates the
 * constraints): the declaration, its value or the map's entries */
static void hybrid_failure(const gen_rt_main_model *m, const gen_rt_main_args *a,
                           const gen_rt_main_run *rn, int st, int k, void *work)
{
    int j = rn->log_which[k] - a->n_ev, i, reset;
    const char *what;
    double t = gen_rt_main_get(m, rn->log_t, k);
    if (j < 0 || j >= m->nh) return;
    reset = m->hybrid_kinds && m->hybrid_kinds[j] == GEN_RT_HYBRID_RESET;
    what = reset ? "reset" : "impact";
    if (st == GEN_RT_ERR_PENETRATED && m->eval_hybrid &&
        !m->eval_hybrid(t, (const char *)rn->log_x + (long)k * m->nx * m->real_size, rn->p,
                        work)) {
        double g = gen_rt_main_get(m, work, j);
        fprintf(stderr, "%s_sim: the run starts inside the %s of %s '%s': its %s is %.12g at "
                "t = %.17g, %s zero, the side its %s (refused: ERR_PENETRATED)\n", m->name,
                reset ? "guard region" : "contact", what, m->hybrid_names[j],
                reset ? "guard" : "gap", g, t, g < 0 ? "below" : "above",
                reset ? "crossing fires into" : "impact closes onto");
        return;
    }
    if (st == GEN_RT_ERR_PENETRATED) return;
    fprintf(stderr, "%s_sim: at %s '%s', t = %.17g: the state after it:", m->name, what,
            m->hybrid_names[j], t);
    for (i = 0; i < m->nx; ++i)
        fprintf(stderr, " %s=%.17g", m->state_names[i],
                gen_rt_main_get(m, rn->log_x_after, (long)k * m->nx + i));
    fprintf(stderr, "\n");
}

/* the run and its CSV: the exit code */
static int run(const gen_rt_main_model *m, const gen_rt_main_args *a, gen_rt_main_run *rn,
               int rows, FILE *out, FILE *ev_out)
{
    const long smv = m->mv > 0 ? m->mv : 1, snr = m->nr > 0 ? m->nr : 1;
    void *t_out = malloc((size_t)rows * (size_t)m->real_size);
    void *x_out = malloc((size_t)rows * (size_t)m->nx * (size_t)m->real_size);
    void *l_out = malloc((size_t)rows * (size_t)smv * (size_t)m->real_size);
    void *r_out = malloc((size_t)rows * (size_t)snr * (size_t)m->real_size);
    void *work = reals(m, (long)(m->mc + m->na + m->ny + m->nh) + 3);
    gen_rt_main_stats stats;
    int failed = 0, st = 0, i;
    int varying = m->nr > 0 && (a->input_csv || a->gain_file || m->tracker);
    rn->rows = rows;
    memset(&stats, 0, sizeof stats);
    stats.x_last = reals(m, m->nx);
    if (!t_out || !x_out || !l_out || !r_out || !work || !stats.x_last) {
        fprintf(stderr, "%s_sim: out of memory for %d rows\n", m->name, rows);
        failed = 1;
    }
    if (!failed && (a->n_ev > 0 || m->nh > 0)) {
        /* with events: the log has room for EVENT_LOG of them; when more
         * were found, the same run again with room for all */
        int cap = GEN_RT_MAIN_EVENT_LOG, pass, n_log;
        int *log_which = NULL;
        void *log_t = NULL, *log_x = NULL, *log_xa = NULL;
        rn->n_events = a->n_ev;
        rn->ev_which = a->ev_which;
        rn->ev_direction = a->ev_dir;
        rn->ev_terminal = a->ev_term;
        rn->ev_level = a->ev_level;
        for (pass = 0; pass < 2 && !failed; ++pass) {
            free(log_which); free(log_t); free(log_x); free(log_xa);
            log_which = (int *)malloc((size_t)cap * sizeof *log_which);
            log_t = malloc((size_t)cap * (size_t)m->real_size);
            log_x = malloc((size_t)cap * (size_t)m->nx * (size_t)m->real_size);
            log_xa = malloc((size_t)cap * (size_t)m->nx * (size_t)m->real_size);
            if (!log_which || !log_t || !log_x || !log_xa) {
                fprintf(stderr, "%s_sim: out of memory for a log of %d events\n", m->name, cap);
                failed = 1;
                break;
            }
            rn->capacity = cap;
            rn->log_which = log_which;
            rn->log_t = log_t;
            rn->log_x = log_x;
            rn->log_x_after = log_xa;
            st = m->simulate(rn, a->x, t_out, x_out, l_out, r_out, &stats);
            if (stats.n_events <= cap) break;
            cap = stats.n_events;
        }
        n_log = failed ? 0 : (stats.n_events < cap ? stats.n_events : cap);
        write_events(m, a, ev_out, n_log, log_which, log_t, log_x, log_xa);
        if (st && m->nh > 0 && n_log > 0 && stats.n_events <= cap)
            hybrid_failure(m, a, rn, st, n_log - 1, work);
        free(log_which); free(log_t); free(log_x); free(log_xa);
        if (ev_out) {
            if (fclose(ev_out) != 0) {
                fprintf(stderr, "%s_sim: error writing %s\n", m->name, a->events_csv);
                failed = 1;
            }
            ev_out = NULL;
        }
    } else if (!failed) {
        st = m->simulate(rn, a->x, t_out, x_out, l_out, r_out, &stats);
    }
    if (st) {
        fprintf(stderr, "%s_sim: step failed at t=%.17g: %s; CSV truncated after %d rows\n",
                m->name, stats.t_last, m->status_message(st), stats.n_out);
        fprintf(stderr, "%s_sim: last good state:", m->name);
        for (i = 0; i < m->nx; ++i)
            fprintf(stderr, " %s=%.17g", m->state_names[i], gen_rt_main_get(m, stats.x_last, i));
        fprintf(stderr, "\n");
        failed = 1;
    }
    if (!failed || stats.n_out > 0)
        if (write_rows(m, a, out, stats.n_out, varying, t_out, x_out, l_out, r_out, work))
            failed = 1;
    free(t_out); free(x_out); free(l_out); free(r_out); free(work); free(stats.x_last);
    if (ev_out) fclose(ev_out);   /* not reached by a run with events */
    return failed;
}

int gen_rt_main(const gen_rt_main_model *m, int argc, char **argv)
{
    gen_rt_main_args a;
    gen_rt_main_run rn;
    void *t_table = NULL, *r_table = NULL, *K = NULL;
    FILE *out = stdout, *ev_out = NULL;
    int st, rows, code;
    if (m->real_size != (int)sizeof(float) && m->real_size != (int)sizeof(double)) {
        fprintf(stderr, "%s_sim: the model's scalar has %d bytes: neither float nor double\n",
                m->name, m->real_size);
        return 1;
    }
    if ((code = gen_rt_main_parse(m, argc, argv, &a)) != GEN_RT_MAIN_CONTINUE) {
        gen_rt_main_free(&a);
        return code;
    }
    memset(&rn, 0, sizeof rn);
    rn.t_end = a.t_end;
    rn.dt = a.dt;
    rn.p = a.p;
    rn.opts = a.opts;
    rn.r = a.r;
    rn.hold = a.hold;
    rn.period = a.period;
    code = 0;
    if (a.input_csv) {
        if (!m->nr) code = fail_usage(m, "this model has no inputs", a.input_csv);
        else code = gen_rt_main_read_inputs(m, a.input_csv, &t_table, &r_table, &rn.n_table);
        rn.t_table = t_table;
        rn.r_table = r_table;
    }
    if (!code && a.gain_file) {
        int n, c, i;
        if (!m->nr) code = fail_usage(m, "this model has no inputs", a.gain_file);
        else if ((code = gen_rt_main_read_csv(m, a.gain_file, &K, &n, &c, NULL, 0)) == 0
                 && (n != m->nr || c != m->ns)) {
            fprintf(stderr, "%s_sim: %s: K must be %d row(s) of %d values (inputs by the "
                    "independent state:", m->name, a.gain_file, m->nr, m->ns);
            for (i = 0; i < m->ns; ++i) fprintf(stderr, " %s", m->ind_names[i]);
            fprintf(stderr, "), got %d x %d\n", n, c);
            code = 2;
        }
        rn.K = K;
        rn.x_op = a.x_op;
    }
    if (!code && a.consistent && (st = m->consistent_state(a.p, a.x))) {
        fprintf(stderr, "%s_sim: no consistent initial state: %s\n", m->name, m->status_message(st));
        code = 1;
    }
    if (!code && a.linearize) {
        code = run_linearize(m, &a);
    } else if (!code) {
        rows = m->simulate_rows(a.t_end, a.dt);
        if (rows < 0) code = fail_usage(m, "bad --t-end/--dt combination", NULL);
        if (!code && a.output && !(out = fopen(a.output, "w"))) {
            fprintf(stderr, "%s_sim: cannot open %s: %s\n", m->name, a.output, strerror(errno));
            out = stdout;
            code = 1;
        }
        if (!code && a.events_csv && !(ev_out = fopen(a.events_csv, "w"))) {
            fprintf(stderr, "%s_sim: cannot open %s: %s\n", m->name, a.events_csv,
                    strerror(errno));
            code = 1;
        }
        if (!code) {
            write_header(m, out, m->nr > 0 && (a.input_csv || a.gain_file || m->tracker));
            code = run(m, &a, &rn, rows, out, ev_out);
        }
        if (out != stdout && fclose(out) != 0 && !code) {
            fprintf(stderr, "%s_sim: error writing %s\n", m->name, a.output);
            code = 1;
        }
    }
    free(t_table); free(r_table); free(K);
    gen_rt_main_free(&a);
    return code;
}
