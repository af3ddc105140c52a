#!/usr/bin/env python3
"""The peer solver of `memstab bench`: scipy's eigsh (ARPACK, shift-invert) on a tangent K
exported by `memstab export-matrix SCENE --out K.mtx`.

    python3 scripts/peer_eigsh.py K.mtx [--k 20] [--sigma S]

Prints one JSON object: {"file", "n", "nnz", "k", "sigma", "eigenvalues" (ascending),
"seconds" (eigsh alone, including its sparse LU of K - sigma I), "read_seconds"}.
The default shift is -1e-3 * max|K_ij|: K of a free body is singular (rigid-body modes),
so sigma = 0 cannot be factorised.
"""
import argparse
import json
import sys
import time

import numpy as np
import scipy.io
import scipy.sparse
import scipy.sparse.linalg


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("matrix")
    ap.add_argument("--k", type=int, default=20)
    ap.add_argument("--sigma", type=float, default=None)
    args = ap.parse_args()
    t0 = time.perf_counter()
    k = scipy.sparse.csc_matrix(scipy.io.mmread(args.matrix))
    read = time.perf_counter() - t0
    sigma = args.sigma
    if sigma is None:
        sigma = -1e-3 * float(abs(k).max())
    t0 = time.perf_counter()
    values = scipy.sparse.linalg.eigsh(
        k, k=args.k, sigma=sigma, which="LM", return_eigenvectors=False
    )
    seconds = time.perf_counter() - t0
    json.dump(
        {
            "file": args.matrix,
            "n": k.shape[0],
            "nnz": int(k.nnz),
            "k": args.k,
            "sigma": sigma,
            "eigenvalues": sorted(float(v) for v in np.asarray(values)),
            "seconds": seconds,
            "read_seconds": read,
        },
        sys.stdout,
    )
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
