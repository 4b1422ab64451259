/* Equilibrium start: contacts (and joint stops) closed at t = 0 preloaded so
 * that a system placed at rest stays at rest.
 *
 * Model: a quasi-static settle. From the pose the scenario gives, with the
 * contacts closed and unloaded, every degree of freedom that some closed
 * contact or stop holds moves by
 * a small delta (a DoF takes part when its column of the Jacobian below
 * changes if every closed contact, stop and friction is let go: a spring, an
 * actuator or gravity alone does not make it take part); sticking contacts
 * and joint frictions move with it, so their
 * anchors take the relative tangential displacement of the two material
 * points (joint friction: the joint's displacement), and the normal
 * penetrations change with the pose. delta solves
 *     udot(delta) = 0     (the generalized accelerations, velocities as given)
 * by Newton iterations with a finite-difference Jacobian and a truncated-SVD
 * (minimum-norm) solve, GSL's gsl_linalg_SV_decomp. This is the state the
 * system would reach if placed gently with infinite damping, without slip.
 * Degrees of freedom nothing holds (a finger still closing, a free body in
 * flight) are left as given. If the friction needed exceeds the cone, the
 * first step of the run finds the slot slipping (physically: it cannot be
 * held). Where it breaks: a pose far from equilibrium (the settle is a
 * Newton solve near the given pose, displacements of the order of load /
 * stiffness), and contact sets that change during the settle (a check point
 * that would touch only after it) are not followed. The work space is
 * allocated here, at reset, with the data's allocator, and freed at once. */
#include "capdyn/sim.h"
#include "../math/cd_math.h"
#include "integ.h"

#include <gsl/gsl_linalg.h>
#include <string.h>

typedef struct {
    int n;                 /* generalized velocities */
    double *y0;            /* (ny) the given pose */
    double *cloc;          /* (nslot x 6) contact point in A's and B's body frames at delta = 0 */
    double *n0;            /* (nslot x 3) normal at delta = 0 */
} eq_ctx;

/* the pose y0 moved by delta (velocity coordinates), anchors following */
static void apply_delta(const cd_model *m, cd_data *d, const eq_ctx *c, const double *delta)
{
    int s, k, i;
    memcpy(d->y, c->y0, (size_t)m->ny * sizeof(double));
    for (s = 0; s < m->nsys; s++) {
        cd_sys_state x = cd_state_of(m, d, s);
        const double *dl = delta + m->sys_v_adr[s];
        int off = 0;
        if (x.pos) {
            double R0[9], Rd[9], R[9], ax[3], th = cd_v3_norm(dl + 3), qn[4];
            cd_v3_add(x.pos, x.pos, dl);
            if (th > 0) {
                cd_v3_scale(ax, dl + 3, 1.0 / th);
                cd_quat_to_m3(R0, x.quat);
                cd_m3_axis_angle(Rd, ax, th);
                cd_m3_mul(R, Rd, R0);
                cd_m3_to_quat(qn, R);
                if (qn[0] * x.quat[0] + qn[1] * x.quat[1] + qn[2] * x.quat[2] + qn[3] * x.quat[3] < 0)
                    for (i = 0; i < 4; i++) qn[i] = -qn[i];
                memcpy(x.quat, qn, sizeof qn);
            }
            off = 6;
        }
        for (i = 0; i < x.njoint; i++) x.q[i] += dl[off + i];
    }
    cd_kinematics(m, d);
    for (k = 0; k < m->nslot; k++) {
        int a = m->cp_body[m->slot_cp[k]], b = m->shape_body[m->slot_shape[k]];
        double pa[3], pb[3], rel[3], zw[3], t[3];
        if (d->slot_mode[k] != CD_MODE_STICK) continue;
        cd_m3_mulv(t, d->body_R + 9 * a, c->cloc + 6 * k);
        cd_v3_add(pa, d->body_x + 3 * a, t);
        cd_m3_mulv(t, d->body_R + 9 * b, c->cloc + 6 * k + 3);
        cd_v3_add(pb, d->body_x + 3 * b, t);
        cd_v3_sub(rel, pa, pb);
        cd_v3_copy(zw, rel);
        cd_v3_axpy(zw, -cd_v3_dot(rel, c->n0 + 3 * k), c->n0 + 3 * k);
        cd_m3_tmulv(d->y + m->ny_slot_adr + 3 * k, d->body_R + 9 * b, zw);
    }
    for (k = 0; k < m->nfric; k++)
        if (d->fric_mode[k] == CD_MODE_STICK) d->y[m->ny_fric_adr + k] = delta[m->body_dof[m->fric_body[k]]];
}

static cd_status residual(const cd_model *m, cd_data *d, const eq_ctx *c, const double *delta, double *r)
{
    apply_delta(m, d, c, delta);
    if (cd_forward(m, d) != CD_OK) return CD_ENUMERIC;
    d->stats.nrhs++;
    memcpy(r, d->udot, (size_t)c->n * sizeof(double));
    return CD_OK;
}

/* The Jacobian d udot / d delta at delta by forward differences of step h,
 * given the residual r0 there; r: n scratch. */
static cd_status fd_jacobian(const cd_model *m, cd_data *d, const eq_ctx *c, double *delta, const double *r0,
                             double *r, double *J, double h)
{
    int n = c->n, i, j;
    cd_status st = CD_OK;
    for (j = 0; j < n && st == CD_OK; j++) {
        delta[j] += h;
        st = residual(m, d, c, delta, r);
        delta[j] -= h;
        for (i = 0; i < n; i++) J[i * n + j] = (r[i] - r0[i]) / h;
    }
    return st;
}

/* The Jacobian (into Jf) with every closed slot and stop let go and every
 * joint friction slipping without torque: what holds nothing. The modes are
 * kept in save (nslot + nlim + 2 nfric words) and restored. r: 2 n scratch. */
static cd_status free_jacobian(const cd_model *m, cd_data *d, const eq_ctx *c, double *delta, double *r,
                               double *Jf, double h, double *save)
{
    int n = c->n, k;
    cd_status st;
    double *r0 = r + n;
    for (k = 0; k < m->nslot; k++) { save[k] = d->slot_mode[k]; d->slot_mode[k] = CD_MODE_OPEN; }
    for (k = 0; k < m->nlim; k++) { save[m->nslot + k] = d->lim_mode[k]; d->lim_mode[k] = CD_LIM_FREE; }
    for (k = 0; k < m->nfric; k++) {
        save[m->nslot + m->nlim + 2 * k] = d->fric_mode[k];
        save[m->nslot + m->nlim + 2 * k + 1] = d->fric_dir[k];
        d->fric_mode[k] = CD_MODE_SLIP;
        d->fric_dir[k] = 0.0;
    }
    st = residual(m, d, c, delta, r0);
    if (st == CD_OK) st = fd_jacobian(m, d, c, delta, r0, r, Jf, h);
    for (k = 0; k < m->nslot; k++) d->slot_mode[k] = (int)save[k];
    for (k = 0; k < m->nlim; k++) d->lim_mode[k] = (int)save[m->nslot + k];
    for (k = 0; k < m->nfric; k++) {
        d->fric_mode[k] = (int)save[m->nslot + m->nlim + 2 * k];
        d->fric_dir[k] = save[m->nslot + m->nlim + 2 * k + 1];
    }
    return st;
}

cd_status cd_equilibrium_start(const cd_model *m, cd_data *d, cd_error *err)
{
    const double fd_h = 1e-8;     /* [m | rad] finite-difference step: load/stiffness is ~1e-9..1e-4 */
    const int max_it = 30, max_pass = 8;
    int n = m->nv, i, j, it, np = 0, pass, tot = 0;
    size_t words = (size_t)(6 * n * n + 10 * n + m->ny + 10 * m->nslot + m->nlim + 2 * m->nfric + 16);
    double *w = d->allocator.alloc(words * sizeof(double), d->allocator.ctx);
    double *J, *V, *S, *work, *r, *r1, *delta, *dx, *save, scale, res = HUGE_VAL;
    int *part, have_msg = 0;
    eq_ctx c;
    cd_status st = CD_OK;
    if (!w) { cd_error_set(err, CD_ENOMEM, "out of memory for the equilibrium start"); return CD_ENOMEM; }
    memset(w, 0, words * sizeof(double));
    J = w; V = J + n * n; S = V + n * n; work = S + n; r = work + n; r1 = r + n; delta = r1 + 2 * n; dx = delta + n;
    c.y0 = dx + n; c.cloc = c.y0 + m->ny; c.n0 = c.cloc + 6 * m->nslot;
    save = c.n0 + 3 * m->nslot;                        /* nslot + nlim + 2 nfric */
    part = (int *)(void *)(save + m->nslot + m->nlim + 2 * m->nfric + 1);   /* n ints in the 4 n n words left */
    c.n = n;
    memcpy(c.y0, d->y, (size_t)m->ny * sizeof(double));
    /* contact points in each body's frame at the given pose */
    if (cd_forward(m, d) != CD_OK) { st = CD_ENUMERIC; goto out; }
    for (i = 0; i < m->nslot; i++) {
        int a = m->cp_body[m->slot_cp[i]], b = m->shape_body[m->slot_shape[i]];
        double t[3];
        cd_v3_sub(t, d->slot_point + 3 * i, d->body_x + 3 * a);
        cd_m3_tmulv(c.cloc + 6 * i, d->body_R + 9 * a, t);
        cd_v3_sub(t, d->slot_point + 3 * i, d->body_x + 3 * b);
        cd_m3_tmulv(c.cloc + 6 * i + 3, d->body_R + 9 * b, t);
        cd_v3_copy(c.n0 + 3 * i, d->slot_normal + 3 * i);
    }
    if ((st = residual(m, d, &c, delta, r)) != CD_OK) goto out;
    scale = 0;
    for (i = 0; i < n; i++) if (fabs(r[i]) > scale) scale = fabs(r[i]);
    if (cd_v3_norm(m->gravity) > scale) scale = cd_v3_norm(m->gravity);
    if (!(scale > 0)) goto out; /* nothing pushes: already in equilibrium */
    /* Contacts are one-sided: a settled contact that pulls (f_n < 0: it
     * touched at the given pose, the settle moved it out) is opened and the
     * settle goes on without it (an active set; at most max_pass passes).
     * Kept closed, it would open at the first step of the run, and the pull
     * the balance relied on would be gone: the system creeps to another
     * equilibrium (a squeezed grasp did, by 0.1 mm: tests/test_capture.c). */
    for (pass = 0; pass < max_pass; pass++) {
        int nopen = 0;
        for (it = 0; it < max_it; it++) {
            gsl_matrix_view Jm, Vm;
            gsl_vector_view Sv, wv, rv, xv;
            double smax;
            int k, ii;
            if ((st = fd_jacobian(m, d, &c, delta, r, r1, J, fd_h)) != CD_OK) goto out;
            if (it == 0) {
                /* the degrees of freedom the closed contacts, stops and frictions
                 * hold: those whose column changes when they are all let go (a
                 * spring, an actuator or gravity alone does not make a DoF take part) */
                double cmax = 0;
                if ((st = free_jacobian(m, d, &c, delta, r1, V, fd_h, save)) != CD_OK) goto out;
                for (j = 0; j < n; j++) {
                    double cn = 0, ca = 0;
                    for (i = 0; i < n; i++) {
                        double dd = J[i * n + j] - V[i * n + j];
                        cn += dd * dd;
                        ca += J[i * n + j] * J[i * n + j];
                    }
                    work[j] = sqrt(cn);
                    if (sqrt(ca) > cmax) cmax = sqrt(ca);
                }
                np = 0;
                for (j = 0; j < n; j++) { part[j] = work[j] > 1e-13 * cmax && cmax > 0; np += part[j]; }
                if (np == 0) goto out;
            }
            res = 0;
            for (i = 0; i < n; i++) if (part[i] && fabs(r[i]) > res) res = fabs(r[i]);
            d->stats.eq_iterations = tot + it + 1;
            d->stats.eq_residual = res;
            if (res <= 1e-14 * scale) break;
            /* the participating block, compacted, solved by truncated SVD */
            for (i = 0, ii = 0; i < n; i++) {
                if (!part[i]) continue;
                for (j = 0, k = 0; j < n; j++)
                    if (part[j]) V[ii * np + k++] = J[i * n + j];
                r1[ii++] = -r[i];
            }
            Jm = gsl_matrix_view_array(V, (size_t)np, (size_t)np);
            Vm = gsl_matrix_view_array(J, (size_t)np, (size_t)np);
            Sv = gsl_vector_view_array(S, (size_t)np);
            wv = gsl_vector_view_array(work, (size_t)np);
            if (gsl_linalg_SV_decomp(&Jm.matrix, &Vm.matrix, &Sv.vector, &wv.vector) != GSL_SUCCESS) { st = CD_ENUMERIC; goto out; }
            smax = S[0];
            for (i = 0; i < np; i++) if (!(S[i] > 1e-12 * smax)) S[i] = 0.0;
            rv = gsl_vector_view_array(r1, (size_t)np);
            xv = gsl_vector_view_array(dx, (size_t)np);
            if (gsl_linalg_SV_solve(&Jm.matrix, &Vm.matrix, &Sv.vector, &rv.vector, &xv.vector) != GSL_SUCCESS) {
                st = CD_ENUMERIC;
                goto out;
            }
            /* backtracking: a law with p_t > 1 has no tangential stiffness at zero
             * deflection, so the first Newton steps can overshoot by far */
            {
                double res_new = HUGE_VAL, lam = 1.0;
                int ls;
                memcpy(r1, delta, (size_t)n * sizeof(double));
                for (ls = 0; ls < 60; ls++, lam *= 0.5) {
                    for (i = n - 1, ii = np - 1; i >= 0; i--)
                        if (part[i]) delta[i] = r1[i] + lam * dx[ii--];
                    if (residual(m, d, &c, delta, r) != CD_OK) continue;
                    res_new = 0;
                    for (i = 0; i < n; i++) if (part[i] && fabs(r[i]) > res_new) res_new = fabs(r[i]);
                    if (res_new < res) break;
                }
                if (!(res_new < res)) { /* no progress: round-off floor reached */
                    memcpy(delta, r1, (size_t)n * sizeof(double));
                    if ((st = residual(m, d, &c, delta, r)) != CD_OK) goto out;
                    break;
                }
            }
        }
        tot += it < max_it ? it + 1 : max_it;
        /* d holds the state at delta: open the contacts that pull */
        for (i = 0; i < m->nslot; i++)
            if (d->slot_mode[i] != CD_MODE_OPEN && d->slot_fn[i] < 0) { d->slot_mode[i] = CD_MODE_OPEN; nopen++; }
        if (!nopen) break;
        if ((st = residual(m, d, &c, delta, r)) != CD_OK) goto out;
    }
    res = 0;
    for (i = 0; i < n; i++) if (part[i] && fabs(r[i]) > res) res = fabs(r[i]);
    d->stats.eq_residual = res;
    if (!(res <= 1e-9 * scale)) {
        cd_error_set(err, CD_ENUMERIC,
                     "equilibrium start: no static equilibrium near the initial pose (largest acceleration left %g, "
                     "%g at the start, after %d Newton iterations): the closed contacts and stops cannot hold the "
                     "bodies there",
                     res, scale, d->stats.eq_iterations);
        st = CD_ENUMERIC;
        have_msg = 1;
    }
out:
    if (st != CD_OK) {
        /* back to the given pose, contacts closed unloaded */
        memcpy(d->y, c.y0, (size_t)m->ny * sizeof(double));
        if (!have_msg) cd_error_set(err, st, "equilibrium start: the state cannot be evaluated (non-finite value or singular mass matrix)");
    }
    d->allocator.free(w, d->allocator.ctx);
    return st;
}
