"""The shape of a tree of links: each link's parent (``Link.parent``: -1 the base, None the
link before, as in a chain), children and ancestors. Parents come before children."""

from __future__ import annotations


def parents(links) -> list[int]:
    """Each link's parent index (-1: the base), parents before children: a chain's when the
    links give none (i - 1)."""
    return [i - 1 if link.parent is None else link.parent for i, link in enumerate(links)]


def is_chain(links) -> bool:
    """Whether the links are a chain: none gives a parent (each one's is the link before)."""
    return all(link.parent is None for link in links)


def children(links) -> list[list[int]]:
    """Each link's children, in increasing order."""
    out = [[] for _ in links]
    for i, p in enumerate(parents(links)):
        if p >= 0:
            out[p].append(i)
    return out


def lineages(links) -> list[set[int]]:
    """Each link with its ancestors, as a set."""
    out: list[set[int]] = []
    for i, p in enumerate(parents(links)):
        out.append({i} | (out[p] if p >= 0 else set()))
    return out


def ancestors(links, i: int) -> list[int]:
    """Link i's ancestors, its parent first."""
    parent, out = parents(links), []
    while parent[i] >= 0:
        i = parent[i]
        out.append(i)
    return out
