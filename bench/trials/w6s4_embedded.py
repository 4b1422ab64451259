#!/usr/bin/env python3
"""W6S4OS (Rahunanthan & Stanescu, "High-order W-methods", J. Comput. Appl.
Math. 233 (2010) 1798-1811) for capdyn's linearly implicit stepper: the
increment form of src/sim/rosw.c, a check of its order as a W-method, and an
embedded order-3 W-solution, which the published method does not have
(docs/performance.md section 19; the trial: bench/trials/w6s4.sh).

The coefficients are the method's transformed form (a = alpha Gamma^-1,
C = I/gamma - Gamma^-1, m = b Gamma^-1, 16 digits) as printed in the
W6S4OS tableau of OrdinaryDiffEq.jl; converted here by Gamma = (I/gamma -
C)^-1, alpha = a Gamma, b = m Gamma, and checked against the row sums c and
d it prints with them.

W-trees: a vertex is f (any number of children, weights through alpha) or
A (the arbitrary matrix, one child, weights through Gamma with its
diagonal). A W-method of order p satisfies, for every W-tree of at most p
vertices, sum_i b_i Phi_i(t) = 1/gamma(t) if t has no A vertex, else 0
(Hairer & Wanner, Solving ODEs II, sec. IV.7). Counts 1, 3, 8, 21 for p = 1..4.

Usage: build/venv/bin/python3 bench/trials/w6s4_embedded.py   (exit 1 if a check fails)
"""
import sys

import numpy as np

A_T = [[0, 0, 0, 0, 0, 0],
       [0.5812383407115008, 0, 0, 0, 0, 0],
       [0.9039624413714670, 1.8615191555345010, 0, 0, 0, 0],
       [2.0765797196750000, 0.1884255381414796, 1.8701589674910320, 0, 0, 0],
       [4.4355506384843120, 5.4571817986101890, 4.6163507880689300, 3.1181119524023610, 0, 0],
       [10.791701698483260, -10.05691522584131, 14.995644854284190, 5.2743399543909430, 1.4297308712611900, 0]]
C_T = [[0, 0, 0, 0, 0, 0],
       [-2.661294105131369, 0, 0, 0, 0, 0],
       [-3.128450202373838, 0, 0, 0, 0, 0],
       [-6.920335474535658, -1.202675288266817, -9.733561811413620, 0, 0, 0],
       [-28.09530629102695, 20.371262954793770, -41.04375275302869, -19.66373175620895, 0, 0],
       [9.7998186780974000, 11.935792886603180, 3.6738749290132010, 14.807828541095500, 0.8318583998690680, 0]]
M_T = [6.4562170746532350, -4.853141317768053, 9.7653183340692600, 2.0810841772787230, 0.6603936866352417, 0.6]
GAMMA = 0.25
D_T = [0.25, 0.0836691184292894, 0.0544718623516351, -0.3402289722355864, 0.0337651588339529, -0.0903074267618540]
C_NODES = [0, 0.1453095851778752, 0.3817422770256738, 0.6367813704374599, 0.7560744496323561, 0.9271047239875670]


def trees(n, memo={}):
    """every W-tree of n vertices: ('f', (children...)) or ('A', child)"""
    if n in memo:
        return memo[n]
    out = []

    def multisets(rem, lo):
        if rem == 0:
            yield ()
            return
        for k in range(1, rem + 1):
            for t in trees(k):
                key = (k, repr(t))
                if key >= lo:
                    for rest in multisets(rem - k, key):
                        yield (t,) + rest

    out += [('f', ch) for ch in multisets(n - 1, (0, ''))]
    if n >= 2:
        out += [('A', t) for t in trees(n - 1)]
    memo[n] = out
    return out


def size(t):
    return 1 + (sum(size(c) for c in t[1]) if t[0] == 'f' else size(t[1]))


def has_a(t):
    return t[0] == 'A' or any(has_a(c) for c in t[1])


def density(t):
    return size(t) * np.prod([density(c) for c in t[1]]) if t[1] else 1.0


def phi(t, al, gm):
    if t[0] == 'A':
        return gm @ phi(t[1], al, gm)
    v = np.ones(al.shape[0])
    for c in t[1]:
        v = v * (al @ phi(c, al, gm))
    return v


def conditions(p):
    return [(n, t, 0.0 if has_a(t) else 1.0 / density(t)) for n in range(1, p + 1) for t in trees(n)]


def stability(bb, B, z):
    return 1 + z * bb @ np.linalg.solve(np.eye(len(bb)) - z * B, np.ones(len(bb)))


def main():
    ok = True
    gm = np.linalg.inv(np.eye(6) / GAMMA - np.array(C_T))
    al = np.array(A_T) @ gm
    b = np.array(M_T) @ gm
    e_d = np.abs(gm.sum(1) - D_T).max()
    e_c = np.abs(al.sum(1) - C_NODES).max()
    print("conversion: row sums of Gamma against d %.1e, of alpha against c %.1e" % (e_d, e_c))
    ok &= e_d < 1e-14 and e_c < 1e-14
    counts = [len(conditions(p)) for p in range(1, 5)]
    print("W-order conditions for p = 1..4:", counts)
    ok &= counts == [1, 3, 8, 21]
    r4 = max(abs(b @ phi(t, al, gm) - v) for n, t, v in conditions(4))
    r5 = max(abs(b @ phi(t, al, gm) - v) for n, t, v in conditions(5) if n == 5)
    print("b: largest residual of the 21 conditions of order <= 4 %.1e; of order 5 %.1e (not 0: order 4)" % (r4, r5))
    ok &= r4 < 1e-14 and r5 > 1e-4
    # the embedded solution: the order-3 conditions have rank 5 on 6 weights
    rows = np.array([phi(t, al, gm) for n, t, v in conditions(3)])
    rank = np.linalg.matrix_rank(rows, 1e-10)
    nv = np.linalg.svd(rows)[2][-1]
    bh = b - b[5] / nv[5] * nv  # the family b + s nv, bhat_6 = 0
    rh3 = max(abs(bh @ phi(t, al, gm) - v) for n, t, v in conditions(3))
    rh4 = np.linalg.norm([(b - bh) @ phi(t, al, gm) for n, t, v in conditions(4) if n == 4])
    print("order-3 conditions: rank %d of 8 rows on 6 weights, so a one-parameter family of order-3 W-solutions" % rank)
    print("bhat (bhat_6 = 0): residual of order <= 3 %.1e, norm of (b - bhat) on the order-4 trees %.3f" % (rh3, rh4))
    ok &= rank == 5 and rh3 < 1e-14 and rh4 > 1e-2
    B = al + gm
    iy = np.logspace(-3, 6, 4000)
    rb = [abs(stability(b, B, 1j * y)) for y in iy]
    k = int(np.argmax(rb))
    print("|R(iy)| of b: max %.4f at y = %.2f (not A-stable by that margin); |R(-1e8)| = %.1e" %
          (rb[k], iy[k], abs(stability(b, B, -1e8))))
    print("|R(iy)| of bhat: max %.2f (the error estimate is filtered by (I - h gam J)^-1, as ROS34PW2's)" %
          max(abs(stability(bh, B, 1j * y)) for y in iy))
    f = lambda x: "%.17g" % (0.0 if abs(x) < 1e-15 else x)
    print("increment form (rosw.c rosw_tab): gam = 0.25")
    print("alpha:", "; ".join(", ".join(f(al[i, j]) for j in range(i)) for i in range(1, 6)))
    print("gamma:", "; ".join(", ".join(f(gm[i, j]) for j in range(i)) for i in range(1, 6)))
    print("b:", ", ".join(f(x) for x in b))
    print("bhat:", ", ".join(f(x) for x in bh))
    print("all checks pass" if ok else "A CHECK FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
