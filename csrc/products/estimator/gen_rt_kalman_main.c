/* gen_rt_kalman_main.c - the standalone program of a Kalman filter: a
 * sensor CSV in, the estimates out (gen_rt_kalman_main.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gen_rt_kalman_main.h"

#ifdef GEN_RT_REAL_FLOAT
#define KM_FMT "%.9g"
#else
#define KM_FMT "%.17g"
#endif

static int usage(const gen_rt_kalman_program *p, const char *why, const char *what)
{
    fprintf(stderr, "%s: %s%s%s\nusage: %s [input.csv] [-o output.csv]\n", p->name, why,
            what ? ": " : "", what ? what : "", p->name);
    return 2;
}

/* split line (modified) at commas into at most max fields */
static int split(char *line, char **fields, int max)
{
    int n = 0;
    char *s = line, *e;
    size_t len = strlen(line);
    while (len && (line[len - 1] == '\n' || line[len - 1] == '\r')) line[--len] = 0;
    for (;;) {
        if (n == max) return -1;
        fields[n++] = s;
        e = strchr(s, ',');
        if (!e) break;
        *e = 0;
        s = e + 1;
    }
    return n;
}

/* the column of name in the header, or -1 */
static int column(char **head, int nh, const char *name)
{
    int i;
    for (i = 0; i < nh; ++i) {
        const char *h = head[i];
        while (*h == ' ') ++h;
        if (strcmp(h, name) == 0) return i;
    }
    return -1;
}

/* a field's value: NaN when empty or nan; *ok = 0 on anything else */
static double field(const char *s, int *ok)
{
    char *end;
    double v;
    while (*s == ' ') ++s;
    if (!*s) return NAN;
    v = strtod(s, &end);
    while (*end == ' ') ++end;
    if (end == s || *end) *ok = 0;
    return v;
}

static void write_row(FILE *out, const gen_rt_kalman_program *p, double t)
{
    const gen_rt_kalman *k = p->k;
    int i;
    fprintf(out, KM_FMT, t);
    for (i = 0; i < p->ns; ++i) fprintf(out, "," KM_FMT, (double)k->xf[i]);
    for (i = 0; i < p->ns; ++i) fprintf(out, "," KM_FMT, sqrt((double)k->P[i * p->ns + i]));
    for (i = 0; i < p->nz; ++i) fprintf(out, ",%d", k->status[i]);
    fprintf(out, "\n");
}

static int run(const gen_rt_kalman_program *p, FILE *in, FILE *out)
{
    static char line[GEN_RT_KALMAN_MAIN_LINE], head_line[GEN_RT_KALMAN_MAIN_LINE];
    char *head[GEN_RT_KALMAN_MAIN_COLS], *f[GEN_RT_KALMAN_MAIN_COLS];
    int ct, cz[GEN_RT_KALMAN_MAIN_COLS], cr[GEN_RT_KALMAN_MAIN_COLS], nh, n, i, st;
    long row = 0;
    gen_rt_kalman *k = p->k;
    if (p->nz > GEN_RT_KALMAN_MAIN_COLS || p->nr > GEN_RT_KALMAN_MAIN_COLS)
        return usage(p, "too many measurements or inputs", NULL);
    if (!fgets(head_line, sizeof head_line, in)) return usage(p, "the input is empty", NULL);
    if ((nh = split(head_line, head, GEN_RT_KALMAN_MAIN_COLS)) < 0)
        return usage(p, "too many columns", NULL);
    if ((ct = column(head, nh, "t")) < 0) return usage(p, "the header has no column", "t");
    for (i = 0; i < p->nz; ++i)
        if ((cz[i] = column(head, nh, p->z_names[i])) < 0)
            return usage(p, "the header has no measurement column", p->z_names[i]);
    for (i = 0; i < p->nr; ++i)
        if ((cr[i] = column(head, nh, p->r_names[i])) < 0)
            return usage(p, "the header has no input column", p->r_names[i]);
    fprintf(out, "t");
    for (i = 0; i < p->ns; ++i) fprintf(out, ",%s", p->state_names[i]);
    for (i = 0; i < p->ns; ++i) fprintf(out, ",sd_%s", p->state_names[i]);
    for (i = 0; i < p->nz; ++i) fprintf(out, ",status_%s", p->z_names[i]);
    fprintf(out, "\n");
    while (fgets(line, sizeof line, in)) {
        int ok = 1;
        double t;
        if (!strchr(line, '\n') && !feof(in)) return usage(p, "a line is too long", NULL);
        if (line[0] == '\n' || line[0] == '\r' || line[0] == 0) continue;
        if ((n = split(line, f, GEN_RT_KALMAN_MAIN_COLS)) != nh)
            return usage(p, "a row's columns differ from the header's", NULL);
        t = field(f[ct], &ok);
        if (row > 0 && (st = gen_rt_kalman_predict(k, p->nr ? p->r : NULL))) goto fail;
        for (i = 0; i < p->nz; ++i) p->z[i] = (gen_rt_real)field(f[cz[i]], &ok);
        for (i = 0; i < p->nr; ++i) p->r[i] = (gen_rt_real)field(f[cr[i]], &ok);
        if (!ok || !(t == t)) return usage(p, "a field is not a number", NULL);
        if (row == 0) {
            k->t = (gen_rt_real)t;
            if ((st = gen_rt_kalman_start(k))) goto fail;
        }
        if ((st = gen_rt_kalman_update(k, p->z))) goto fail;
        write_row(out, p, t);
        ++row;
    }
    return 0;
fail:
    fprintf(stderr, "%s: row %ld: %s\n", p->name, row, gen_rt_status_message(st));
    return 1;
}

int gen_rt_kalman_main(int argc, char **argv, const gen_rt_kalman_program *prog)
{
    const char *in_path = NULL, *out_path = NULL;
    FILE *in = stdin, *out = stdout;
    int i, code;
    for (i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "-o") == 0 && i + 1 < argc) out_path = argv[++i];
        else if (strcmp(argv[i], "-h") == 0 || strcmp(argv[i], "--help") == 0) {
            printf("usage: %s [input.csv] [-o output.csv]\n", prog->name);
            return 0;
        } else if (!in_path && argv[i][0] != '-') in_path = argv[i];
        else return usage(prog, "unknown argument", argv[i]);
    }
    if (in_path && !(in = fopen(in_path, "r"))) return usage(prog, "cannot read", in_path);
    if (out_path && !(out = fopen(out_path, "w"))) {
        if (in != stdin) fclose(in);
        return usage(prog, "cannot write", out_path);
    }
    code = run(prog, in, out);
    if (in != stdin) fclose(in);
    if (out != stdout && fclose(out) && !code) code = usage(prog, "error writing", out_path);
    return code;
}
