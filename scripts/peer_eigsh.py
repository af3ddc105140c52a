#!/usr/bin/env python3
"""The peer solver of `memstab bench`: scipy's eigsh (ARPACK, shift-invert) on a tangent K
exported by `memstab export-matrix SCENE --out K.mtx`.

    python3 scripts/peer_eigsh.py K.mtx [--k 20] [--sigma S]

K.mtx holds the sparse part S of K (Matrix Market `coordinate real symmetric`). When K also
has rank-one terms (a `gas-amount` effect: K = S + sum_k c_k a_k a_k^T, dense), K.mtx names a
companion file on a comment line `% rank-one file: K.rank1.mtx` (same directory): a Matrix
Market `array real general` n x r matrix whose column k is a_k, with the coefficients on a
comment line `% coefficients: c_1 ... c_r`. Only that comment line makes the script read a
companion file.

- Sparse K (no rank-one terms): `eigsh(K, k, sigma, which='LM')`, scipy factorising K - sigma I
  itself (SuperLU).
- K with rank-one terms: A = K is passed as a LinearOperator (x -> S x + U (c * U^T x)) and
  (K - sigma I)^-1 as `OPinv`, by a sparse LU of S - sigma I (scipy `splu`, SuperLU as above)
  and the Sherman-Morrison-Woodbury formula with U = [a_1 ... a_r], C = diag(c):
      (S - sigma I + U C U^T)^-1 x = y - W (I + C U^T W)^-1 C U^T y,
      y = (S - sigma I)^-1 x,  W = (S - sigma I)^-1 U  (r extra solves, once).

Prints one JSON object: {"file", "n", "nnz" (of S), "rank_one_terms", "k", "sigma",
"eigenvalues" (ascending, of K), "scale" (max|K_ij|, with rank-one terms the larger of max|S_ij|
and max_k |c_k| max_i a_ki^2: the unit of `memstab spectrum`), "units" ("max|K_ij|"),
"relative" (the eigenvalues in units of "scale", as `memstab spectrum` prints them), "seconds" (eigsh alone, including the factorisation of
K - sigma I and, with rank-one terms, the Woodbury set-up), "read_seconds"}.
The default shift is -1e-3 * max|K_ij| (with rank-one terms: the larger of max|S_ij| and
max_k |c_k| max_i a_ki^2): K of a free body is singular (rigid-body modes), so sigma = 0
cannot be factorised.
"""
import argparse
import json
import os
import sys
import time

import numpy as np
import scipy.io
import scipy.sparse
import scipy.sparse.linalg

RANK_ONE_FILE_TAG = "rank-one file:"
COEFFICIENTS_TAG = "coefficients:"


def comment_lines(path):
    """The comment lines of a Matrix Market file (without the leading '%'), header excluded."""
    out = []
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("%%"):
                continue
            if not line.startswith("%"):
                break
            out.append(line[1:].strip())
    return out


def read_rank_one(matrix_path):
    """(U, c) of the rank-one terms named in K.mtx's comments, or None."""
    name = None
    for line in comment_lines(matrix_path):
        if line.startswith(RANK_ONE_FILE_TAG):
            name = line[len(RANK_ONE_FILE_TAG):].strip()
            break
    if name is None:
        return None
    path = os.path.join(os.path.dirname(os.path.abspath(matrix_path)), name)
    coefficients = None
    for line in comment_lines(path):
        if line.startswith(COEFFICIENTS_TAG):
            coefficients = [float(t) for t in line[len(COEFFICIENTS_TAG):].split()]
            break
    if coefficients is None:
        sys.exit(f"{path}: no '% {COEFFICIENTS_TAG} ...' comment line")
    u = np.asarray(scipy.io.mmread(path), dtype=float)
    if u.ndim == 1:
        u = u.reshape(-1, 1)
    if u.shape[1] != len(coefficients):
        sys.exit(f"{path}: {u.shape[1]} columns but {len(coefficients)} coefficients")
    return u, np.asarray(coefficients, dtype=float)


def eigsh_with_rank_one(s, u, c, k, sigma):
    """eigsh on K = S + U diag(c) U^T, shift-invert by sparse LU + Woodbury."""
    n = s.shape[0]
    lu = scipy.sparse.linalg.splu(
        (s - sigma * scipy.sparse.identity(n, format="csc")).tocsc()
    )
    w = lu.solve(u)  # (S - sigma I)^-1 U, n x r
    small = np.eye(len(c)) + c[:, None] * (u.T @ w)  # I + C U^T W, r x r

    def op_inv(x):
        x = np.asarray(x, dtype=float).reshape(-1)
        y = lu.solve(x)
        z = np.linalg.solve(small, c * (u.T @ y))
        return y - w @ z

    def op(x):
        x = np.asarray(x, dtype=float).reshape(-1)
        return s @ x + u @ (c * (u.T @ x))

    a = scipy.sparse.linalg.LinearOperator((n, n), matvec=op, dtype=float)
    opinv = scipy.sparse.linalg.LinearOperator((n, n), matvec=op_inv, dtype=float)
    return scipy.sparse.linalg.eigsh(
        a, k=k, sigma=sigma, which="LM", OPinv=opinv, return_eigenvectors=False
    )


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("matrix")
    ap.add_argument("--k", type=int, default=20)
    ap.add_argument("--sigma", type=float, default=None)
    args = ap.parse_args()
    t0 = time.perf_counter()
    s = scipy.sparse.csc_matrix(scipy.io.mmread(args.matrix))
    rank_one = read_rank_one(args.matrix)
    read = time.perf_counter() - t0
    # max|K_ij| as `memstab spectrum` measures it: of S, and of each rank-one term's largest
    # entry c_k max_i a_ki^2.
    scale = float(abs(s).max())
    if rank_one is not None:
        u, c = rank_one
        scale = max(scale, float(np.max(np.abs(c) * np.max(u * u, axis=0))))
    scale = max(scale, 1e-300)
    sigma = args.sigma
    if sigma is None:
        sigma = -1e-3 * scale
    t0 = time.perf_counter()
    if rank_one is None:
        values = scipy.sparse.linalg.eigsh(
            s, k=args.k, sigma=sigma, which="LM", return_eigenvectors=False
        )
    else:
        values = eigsh_with_rank_one(s, rank_one[0], rank_one[1], args.k, sigma)
    seconds = time.perf_counter() - t0
    json.dump(
        {
            "file": args.matrix,
            "n": s.shape[0],
            "nnz": int(s.nnz),
            "rank_one_terms": 0 if rank_one is None else int(len(rank_one[1])),
            "k": args.k,
            "sigma": sigma,
            "eigenvalues": sorted(float(v) for v in np.asarray(values)),
            "scale": scale,
            "units": "max|K_ij|",
            "relative": sorted(float(v) / scale for v in np.asarray(values)),
            "seconds": seconds,
            "read_seconds": read,
        },
        sys.stdout,
    )
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
