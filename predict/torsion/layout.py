"""Shape of a torsional system's spring graph: a chain (in order), a tree, or one with loops.

The eigen-solver is chosen by the shape (:mod:`predict.torsion.eigen`): chains by bidiagonal
dqds, trees by bisection, anything with a closed loop of springs by dense ``eigh``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["classify"]


def classify(n_nodes: int, edges: np.ndarray, stiffnesses: np.ndarray, mask: np.ndarray):
    """Classify the undamped spring graph of the nodes in ``mask``.

    Parameters
    ----------
    n_nodes : int
    edges : ndarray (m, 2) of int
        Spring ends, ``-1`` = ground.
    stiffnesses : ndarray (m,)
        N·m/rad; zero-stiffness (damping-only) links are left out.
    mask : ndarray (n_nodes,) of bool
        Nodes in the undamped analysis.

    Returns
    -------
    kind : {'chain', 'tree', 'dense'}
    info : dict
        ``nodes`` (indices kept), ``a``, ``b``, ``k`` (kept springs, ends renumbered); for a
        chain also ``order`` (node sequence), ``chain_k`` (stiffnesses along it, the ground
        spring first) and ``grounded``.

    Examples
    --------
    >>> import numpy as np
    >>> kind, info = classify(3, np.array([[2, 1], [1, 0]]), np.array([5.0, 7.0]),
    ...                       np.ones(3, bool))
    >>> print(kind, info["order"], info["chain_k"], info["grounded"])
    chain [0 1 2] [7. 5.] False
    """
    n, e, k = n_nodes, edges, stiffnesses
    if len(k) in (n - 1, n) and mask.all() and k.min(initial=1.0) > 0:
        # fast path: a chain as chain() builds it (free, or grounded at node 0), edges
        # (i, i+1) for i = 0..n-2, preceded by (-1, 0) when grounded
        first = np.arange(n - 1 - len(k), n - 1)
        if np.array_equal(e[:, 0], first) and np.array_equal(e[:, 1], first + 1):
            order = np.arange(n)
            info = dict(nodes=order, a=e[:, 0], b=e[:, 1], k=k,
                        order=order, chain_k=k, grounded=len(k) == n)
            return "chain", info
    keep_e = (stiffnesses > 0) & mask[edges[:, 1]] & (
        (edges[:, 0] < 0) | mask[np.maximum(edges[:, 0], 0)])
    nodes = np.flatnonzero(mask)
    remap = -np.ones(n_nodes, int)
    remap[nodes] = np.arange(nodes.size)
    e = edges[keep_e]
    a = np.where(e[:, 0] < 0, -1, remap[np.maximum(e[:, 0], 0)])
    b = remap[e[:, 1]]
    k = stiffnesses[keep_e]
    nn = nodes.size
    # forest test with ground as an extra vertex (union-find)
    parent = list(range(nn + 1))

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    forest = True
    for u, v in zip(a, b):
        ru, rv = find(nn if u < 0 else u), find(v)
        if ru == rv:
            forest = False
            break
        parent[ru] = rv
    info = dict(nodes=nodes, a=a, b=b, k=k)
    if not forest:
        return "dense", info
    n_ground = int(np.sum(a < 0))
    inner = a >= 0
    deg = np.bincount(np.concatenate([a[inner], b[inner]]), minlength=nn)
    connected = (len(k) - n_ground) == nn - 1
    if connected and deg.max(initial=0) <= 2 and n_ground <= 1:
        ends = np.flatnonzero(deg <= 1)
        start = ends[0] if nn > 1 else 0
        if n_ground == 1:
            g = int(b[a < 0][0])
            if deg[g] > 1:
                return "tree", info
            start = g
        nbr = [[] for _ in range(nn)]
        for u, v, kk in zip(a[inner], b[inner], k[inner]):
            nbr[u].append((v, kk))
            nbr[v].append((u, kk))
        order, ks, prev, cur = [start], [], -1, start
        while len(order) < nn:
            (nxt, kk), = [(v, kk) for v, kk in nbr[cur] if v != prev]
            order.append(nxt)
            ks.append(kk)
            prev, cur = cur, nxt
        if n_ground == 1:
            ks = [float(k[a < 0][0])] + ks
        info.update(order=np.asarray(order), chain_k=np.asarray(ks, float),
                    grounded=n_ground == 1)
        return "chain", info
    return "tree", info
