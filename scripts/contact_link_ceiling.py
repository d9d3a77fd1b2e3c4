#!/usr/bin/env python3
"""How well can a classifier name the contact link from the joint torques alone, for the contact
distribution of scripts/make_validation_collisions.py (point = the link's centre of mass + U(+-4 cm)^3
in the body frame, direction isotropic, peak joint torque 3/5/8/11 N·m), with white noise on each
joint's torque? Monte Carlo over random UR3e poses near home. The classifier is the Bayesian model
choice of src/monitor/diagnosis.cpp (link_evidence): each link's evidence integrates the force under
a Gaussian prior (closed form) over a log grid of scales, and the contact point over a prior region:
  - "generator box": the generator's own +-4 cm cube (knows the test distribution: a ceiling check);
  - "inertia box":   the link's equivalent inertia box (what the monitor uses; generator-independent).
Its accuracy is achievable, so it bounds the best possible classifier from below.
Needs Debian's python3 with numpy:  /usr/bin/python3 scripts/contact_link_ceiling.py [SEED] [TRIALS]
Session 11, `scripts/contact_link_ceiling.py 7 300` (Monte Carlo scatter about +-1.7 %): generator box
89.7 % of links named at the observer's per-sample noise, 97.7 % at a third of it; inertia box 91.0 %
and 95.0 %."""
import json, math, sys
import numpy as np
rng = np.random.default_rng(int(sys.argv[1]) if len(sys.argv) > 1 else 7)
TRIALS = int(sys.argv[2]) if len(sys.argv) > 2 else 300
import os
R = json.load(open(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'data', 'robots', 'ur3e.json')))
J = R['joints']
def rx(a):
    c, s = math.cos(a), math.sin(a); T = np.eye(4); T[1:3,1:3] = [[c,-s],[s,c]]; return T
def rz(a):
    c, s = math.cos(a), math.sin(a); T = np.eye(4); T[0:2,0:2] = [[c,-s],[s,c]]; return T
def tz(d): T = np.eye(4); T[2,3] = d; return T
def tx(a): T = np.eye(4); T[0,3] = a; return T
COM = []
for jd in J:
    x, y, z = jd['com']; ca, sa = math.cos(jd['alpha']), math.sin(jd['alpha'])
    COM.append(np.array([jd['a'] + x, ca*y - sa*z, jd['d'] + sa*y + ca*z]))
def frames(q):
    T = np.eye(4); Ts = [T]; B = []   # Ts[i] = DH frame i (0 = base); B[i] = body i+1 frame
    for i, jd in enumerate(J):
        Bi = T @ rz(q[i] + jd['theta_offset']); B.append(Bi)
        T = Bi @ tz(jd['d']) @ tx(jd['a']) @ rx(jd['alpha']); Ts.append(T)
    return Ts, B
def jac_t(q, Ts, B, link, pts):
    """tau per unit force: (npts, 6 joints, 3) for points pts (npts,3) in body frame of link (0-based)"""
    Bl = B[link]
    P = (Bl[:3,:3] @ pts.T).T + Bl[:3,3]
    out = np.zeros((len(pts), 6, 3))
    for j in range(link + 1):
        z = Ts[j][:3,2]; o = Ts[j][:3,3]
        r = P - o
        # tau_j = z . (r x F) = (z x r)^T . F ... careful: z.(r x F) = F.(z x r)
        out[:, j, :] = np.cross(z, r)
    return out
HOME = np.array([0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0])
MAGS = [3, 5, 8, 11]
HALF = []
ROT = []
for jd in J:
    m = jd['mass']; xx, xy, xz, yy, yz, zz = jd['inertia']
    ev = [yy + zz - xx, xx + zz - yy, xx + yy - zz]
    HALF.append(np.array([0.5 * math.sqrt(max(6 * e / m, 0)) for e in ev]))
    ROT.append(rx(jd['alpha'])[:3, :3])
def prior_box(k, n):
    d = rng.uniform(-1, 1, (n, 3)) * HALF[k]
    return COM[k] + (ROT[k] @ d.T).T
def run2(sigma, prior, trials=None, npts=400, scales=np.geomspace(2, 400, 14), truth_half=0.04):
    trials = trials or TRIALS
    ok = 0; okp = np.zeros(6); cnt = np.zeros(6)
    for t in range(trials):
        q = HOME + rng.uniform(-0.6, 0.6, 6)
        Ts, B = frames(q)
        l = t % 6
        p = COM[l] + rng.uniform(-truth_half, truth_half, 3)
        d = rng.normal(size=3); d /= np.linalg.norm(d)
        u = jac_t(q, Ts, B, l, p[None])[0] @ d
        m = MAGS[(t // 6) % 4]
        y = m * u / np.abs(u).max() + sigma * rng.normal(size=6)
        W = 1.0 / sigma; yw = y * W
        logL = []
        for k in range(6):
            pts = prior(k, npts)
            A = jac_t(q, Ts, B, k, pts) * W[None, :, None]
            lls = []
            for s in scales:
                C = s * s * np.einsum('pij,pkj->pik', A, A) + np.eye(6)[None]
                _, logdet = np.linalg.slogdet(C)
                sol = np.linalg.solve(C, np.broadcast_to(yw, (npts, 6))[..., None])[..., 0]
                lls.append(-0.5 * (sol @ yw + logdet))
            ll = np.stack(lls); mx = ll.max(); logL.append(mx + math.log(np.exp(ll - mx).mean()))
        pred = int(np.argmax(logL)); ok += pred == l; okp[l] += pred == l; cnt[l] += 1
    return ok / trials, okp / cnt
# the momentum observer's per-sample noise on the simulated UR3e (J1..J6, N·m; docs/validation.md)
SIG = np.array([0.17, 0.21, 0.11, 0.055, 0.043, 0.044])
cube = lambda k, n: COM[k] + rng.uniform(-0.04, 0.04, (n, 3))
for name, s, pr in [('generator box, noise', SIG, cube), ('generator box, noise/3', SIG / 3, cube),
                    ('inertia box, noise', SIG, prior_box), ('inertia box, noise/3', SIG / 3, prior_box)]:
    acc, per = run2(s, pr)
    print(f'{name:24s} links named {acc:.3f}  per link {np.round(per, 2)}', flush=True)
