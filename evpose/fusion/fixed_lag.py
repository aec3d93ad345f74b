"""A fixed-lag iSAM2 smoother whose whole state can be copied: constant-cost snapshots of the fusion graph.

gtsam's ``IncrementalFixedLagSmoother`` cannot be copied or pickled from
Python, so a snapshot of the fusion had to replay every input since
initialisation. This class does what ``IncrementalFixedLagSmoother::update``
does (gtsam 4.3: gtsam/nonlinear/IncrementalFixedLagSmoother.cpp), on a plain
``gtsam.ISAM2``, which has a (deep) copy constructor:

1. record the new keys' timestamps; the current time is the newest timestamp;
2. the keys older than ``current - lag`` are to be marginalised;
3. if there are any, constrain the iSAM2 ordering so they are eliminated first
   (group 0, every other key of the window group 1), and mark for
   re-elimination the cliques that would keep them from being leaves (gtsam
   4.3's ``BayesTreeMarginalizationHelper``, see :func:`keys_to_reeliminate`);
4. ``ISAM2.update`` with the new factors, values, that ordering constraint and
   those extra keys;
5. ``ISAM2.marginalizeLeaves`` on them (in timestamp order, keys ascending
   within one timestamp: the order of gtsam's timestamp multimap), then forget
   their timestamps.

The Bayes tree's cliques are not reachable from the Python wrapper, but
``ISAM2.dot`` prints them (frontal keys in order, parent keys, parent -> child
edges) in a few microseconds, which is all the helper needs. The tests check
the estimates equal gtsam's smoother bit for bit over long runs with outliers
and tracking losses (with :attr:`~CopyableFixedLagSmoother.rebase_every` off).

``ISAM2`` itself cannot be pickled either, but its factors (the marginals of
the keys gone included, as ``LinearContainerFactor``), its linearisation point
and the timestamps serialise. With ``rebase_every`` set the smoother
periodically *re-bases*: it rebuilds iSAM2 from exactly that content with one
batch update (:meth:`~CopyableFixedLagSmoother.rebase`), so its state is a
function of the last re-base's content and the calls since, and a stored state
(the viewer's disk snapshots) is restored at a cost that does not depend on the
step instead of by replaying every call since step 0. It changes the
algorithm slightly (the window is re-eliminated at its linearisation point,
which iSAM2 does only partly), headless as well; measured with every 50 states:
fused positions within 0.09 mm (median 0.001 mm) of a never re-based run on a
10 s synthetic flight, ``full`` on the 2 s landings (seeds 0-3) 9.152 / 9.510 mm
(9.151 / 9.510 never re-based), the demo 15.979 mm either way; 0.5 ms per
re-base (~0.01 ms per update, against ~0.75 ms for the update itself).

Not kept (session 12, the demo's fusion calls replayed, paired in one process, same estimates): leaving the newest
keys in ordering group 2 between updates and writing only the difference (half the ``KeyGroupMap`` calls) changed
the update's CPU by 0.98-1.00x; gtsam's key names built in Python instead of ``DefaultKeyFormatter``, together with
``FusedState.copy`` by ``ndarray.copy``, 0.99-1.00x.
"""

from __future__ import annotations

import bisect


def parse_bayes_tree(dot: str) -> tuple[dict[str, tuple[list[str], str]], dict[str, list[str]], dict[str, str]]:
    """The Bayes tree printed by ``ISAM2.dot()``: clique id -> (frontal key names in elimination order, parent key
    names joined by ", "), clique id -> child ids, key name -> id of the clique holding it as a frontal.

    Names are left as printed (gtsam's default key formatter, C++-side: a Python
    formatter would cost a callback per key); node lines read
    ``id[label="f1, f2 : p1, p2"];`` (no " : " at a root), edges ``parent->child``.
    """
    cliques: dict[str, tuple[list[str], str]] = {}
    children: dict[str, list[str]] = {}
    owner: dict[str, str] = {}
    for line in dot.split("\n"):  # a line loop with str.partition: ~4x faster than re.findall here
        if line.endswith('"];'):
            cid, _, label = line.partition('[label="')
            frontal, _, parents = label[:-3].partition(" : ")
            names = frontal.split(", ")
            cliques[cid] = (names, parents)
            for n in names:
                owner[n] = cid
        elif "->" in line:
            parent, _, child = line.partition("->")
            children.setdefault(parent, []).append(child)
    return cliques, children, owner


def _only_in_leaf_cliques(dot: str, marginalize: dict[int, str]) -> bool:
    """Fast path (~2 us): every key to marginalise sits in a childless clique whose frontals are all marginalised.

    gtsam 4.3 names each clique in the dot output after its first frontal key,
    so the candidate cliques are found with a few substring searches. Anything
    else (or another naming) returns False and takes the full analysis.
    """
    names = set(marginalize.values())
    covered: set[str] = set()
    for key in marginalize:
        head = f"\n{key}[label=\""
        i = dot.find(head)
        if i < 0:
            continue
        i += len(head)
        frontal = dot[i : dot.find('"', i)].partition(" : ")[0].split(", ")
        if not names.issuperset(frontal) or f"\n{key}->" in dot:
            return False
        covered.update(frontal)
    return covered == names


def keys_to_reeliminate(dot: str, marginalize: set[str]) -> set[str]:
    """Key names iSAM2 must re-eliminate so that ``marginalize`` end up in leaf cliques: gtsam 4.3's
    ``BayesTreeMarginalizationHelper::gatherAdditionalKeysToReEliminate``, re-derived on the printed tree.

    A clique holding a key to marginalise needs re-elimination if a kept key
    precedes it among the clique's frontals, or a child depends on it and that
    child's subtree holds kept keys; then so do its descendants that depend on
    marginalised keys and whose subtrees hold kept keys. The result is a set
    (iSAM2 merges it into an ordered key set), so visiting order does not matter.
    """
    cliques, children, owner = parse_bayes_tree(dot)
    whole: dict[str, bool] = {}
    parent_sets: dict[str, set[str]] = {}

    def parents(c: str) -> set[str]:
        # Memoised: needs() asks for every child once per frontal key, and splitting the printed separator each time
        # cost ~0.18 ms per fusion update (session 18 profile, 346x260 landing).
        if c not in parent_sets:
            p = cliques[c][1]
            parent_sets[c] = set(p.split(", ")) if p else set()
        return parent_sets[c]

    def whole_subtree(c: str) -> bool:
        if c not in whole:
            whole[c] = all(k in marginalize for k in cliques[c][0]) and all(whole_subtree(ch) for ch in children.get(c, ()))
        return whole[c]

    def needs(c: str) -> bool:
        kept_ahead = False
        for k in cliques[c][0]:
            if k not in marginalize:
                kept_ahead = True
            elif kept_ahead or any(k in parents(ch) and not whole_subtree(ch) for ch in children.get(c, ())):
                return True
        return False

    extra: set[str] = set()
    for c in {owner[k] for k in marginalize}:
        if c in extra or not needs(c):
            continue
        extra.add(c)
        queue = [ch for ch in children.get(c, ()) if ch not in extra and parents(ch) & marginalize]
        while queue:
            d = queue.pop(0)
            if not whole_subtree(d):
                extra.add(d)
                queue.extend(ch for ch in children.get(d, ()) if ch not in extra)
    return {k for c in extra for k in cliques[c][0]}


class CopyableFixedLagSmoother:
    """iSAM2 fixed-lag smoother (gtsam ``IncrementalFixedLagSmoother`` semantics) with :meth:`copy`.

    ``lag`` is in the caller's timestamp unit (the fusion uses the state index).
    """

    def __init__(self, lag: float, params, _isam=None, rebase_every: float | None = None, newest_last: bool = False):
        import gtsam

        self._gtsam = gtsam
        self.lag = float(lag)
        self.params = params
        self.rebase_every = None if not rebase_every else float(rebase_every)
        """When set, the first update whose newest timestamp reaches a new multiple of it first re-bases the smoother
        (:meth:`rebase`), in the timestamp unit; None: never (gtsam's smoother exactly)."""
        self.newest_last = bool(newest_last)
        """In an update that marginalises, the keys of the newest and the previous newest timestamp (those the new
        factors of a filter-like graph touch) form a third ordering group, eliminated last, as plain iSAM2 orders
        the keys of new factors; False: gtsam's smoother exactly (every kept key in one group). See
        ``FusionConfig.newest_state_last``."""
        self.isam = gtsam.ISAM2(params) if _isam is None else _isam
        # Ascending timestamps and their keys (in insertion order): gtsam's timestamp -> key multimap.
        self._stamps: list[float] = []
        self._keys: list[list[int]] = []
        self._stamp_of: dict[int, float] = {}
        self._name_of: dict[int, str] = {}  # key -> name as ISAM2.dot prints it, and back
        self._key_of: dict[str, int] = {}
        # Every key of the window in ordering group 1, kept up to date instead of rebuilt per update (a
        # pybind call per key); the keys to marginalise move to group 0 for the one update that needs it.
        self._groups = gtsam.KeyGroupMap()
        self.journal: list | None = None
        """When a list (the viewer's disk snapshots turn it on), every call that changes or reads the iSAM2 state is
        appended: ``("update", graph, values, timestamps)`` or ``(estimate method name, key)``. iSAM2 cannot be
        pickled, but replaying these calls on a copy of an earlier state (:meth:`replay`) gives the same smoother
        bit for bit (reads matter too: an estimate updates iSAM2's lazily computed delta). A re-base restarts it
        with ``("rebase", graph, values, stamps)``, its content (what came before is not needed any more). A copy
        does not journal."""

    def copy(self) -> "CopyableFixedLagSmoother":
        """An independent deep copy (the iSAM2 copy constructor clones the Bayes tree, values and factors)."""
        other = CopyableFixedLagSmoother(self.lag, self.params, self._gtsam.ISAM2(self.isam), self.rebase_every, self.newest_last)
        other._stamps = list(self._stamps)
        other._keys = [list(k) for k in self._keys]
        other._stamp_of = dict(self._stamp_of)
        other._name_of = dict(self._name_of)
        other._key_of = dict(self._key_of)
        for key in self._stamp_of:
            other._groups.insert2(key, 1)
        return other

    def update(self, graph=None, values=None, timestamps: dict | None = None, remove: list[int] | None = None,
               force_relinearize: bool = False) -> list[int]:
        """Add factors and new variables with their timestamps, remove the factors at the indices ``remove`` (as
        returned by an earlier update), update iSAM2, marginalise keys older than the lag (re-based first when the
        newest timestamp reaches a new multiple of :attr:`rebase_every`). Returns the new factors' indices.
        ``force_relinearize``: relinearise every variable whose delta exceeds the threshold in this update, whatever
        the params' ``relinearizeSkip``."""
        if timestamps and self.rebase_every and self._stamps:
            every = self.rebase_every
            if max(timestamps.values()) // every > self._stamps[-1] // every:
                moved = self.rebase()
                if remove:
                    remove = [moved[i] for i in remove if i in moved]
        if self.journal is not None:
            entry = ("update", graph, values, None if timestamps is None else dict(timestamps))
            if force_relinearize:
                entry += (list(remove) if remove else None, True)
            elif remove:
                entry += (list(remove),)
            self.journal.append(entry)
        return self._update(graph, values, timestamps, remove, force_relinearize)

    def _update(self, graph, values, timestamps, remove=None, force=False) -> list[int]:
        gtsam = self._gtsam
        hot = list(self._keys[-1]) + [int(k) for k in timestamps] if self.newest_last and timestamps and self._stamps else []
        if timestamps:
            for key, stamp in sorted(timestamps.items()):  # gtsam walks its std::map<Key, double>: keys ascending
                self._insert(int(key), float(stamp))
        cut = bisect.bisect_left(self._stamps, self._stamps[-1] - self.lag) if self._stamps else 0
        if not cut:
            if force:
                result = self.isam.update(gtsam.NonlinearFactorGraph() if graph is None else graph,
                                          gtsam.Values() if values is None else values, list(remove) if remove else [], None, None,
                                          None, True)
            elif remove:
                result = self.isam.update(gtsam.NonlinearFactorGraph() if graph is None else graph,
                                          gtsam.Values() if values is None else values, list(remove))
            else:
                result = self.isam.update(gtsam.NonlinearFactorGraph() if graph is None else graph,
                                          gtsam.Values() if values is None else values)
            return list(result.getNewFactorsIndices()) if graph is not None else []
        marginalize = [key for keys in self._keys[:cut] for key in keys]
        dot = self.isam.dot()
        names = {key: self._name_of[key] for key in marginalize}
        extra = None
        if not _only_in_leaf_cliques(dot, names):  # the usual case needs no extra keys
            extra = gtsam.KeyList()
            for name in sorted(keys_to_reeliminate(dot, set(names.values()))):
                extra.push_back(self._key_of[name])
        groups = self._groups
        for key in marginalize:  # eliminated first (KeyGroupMap.insert2 does not overwrite: erase first)
            groups.erase(key)
            groups.insert2(key, 0)
        if hot:
            gone = set(marginalize)
            hot = [key for key in dict.fromkeys(hot) if key not in gone]
            for key in hot:  # eliminated last: the newest state at the root (see ``newest_last``)
                groups.erase(key)
                groups.insert2(key, 2)
        result = self.isam.update(gtsam.NonlinearFactorGraph() if graph is None else graph,
                                  gtsam.Values() if values is None else values, list(remove) if remove else [], groups, None, extra, bool(force))
        for key in hot:
            groups.erase(key)
            groups.insert2(key, 1)
        leaves = gtsam.KeyList()
        for key in marginalize:
            leaves.push_back(key)
        self.isam.marginalizeLeaves(leaves)
        for key in marginalize:
            groups.erase(key)
            del self._stamp_of[key], self._key_of[self._name_of.pop(key)]
        del self._stamps[:cut], self._keys[:cut]
        return list(result.getNewFactorsIndices()) if graph is not None else []

    def content(self):
        """What the smoother is, in objects gtsam serialises: ``(factors, linearisation point, timestamps)`` -- the
        factors of the window (marginals of the keys gone as ``LinearContainerFactor``) without iSAM2's empty
        slots, iSAM2's linearisation point (a copy), and ``[(stamp, [keys in insertion order]), ...]`` ascending."""
        return self._content()[:3]

    def _content(self):
        """:meth:`content` and the map from each factor's iSAM2 index to its index in the content's graph."""
        gtsam = self._gtsam
        factors = self.isam.getFactorsUnsafe()
        graph = gtsam.NonlinearFactorGraph()
        moved = {}
        for i in range(factors.size()):
            f = factors.at(i)
            if f is not None:
                moved[i] = graph.size()
                graph.push_back(f)  # factors are immutable: shared, not copied
        return graph, gtsam.Values(self.isam.getLinearizationPoint()), [(s, list(k)) for s, k in zip(self._stamps, self._keys)], moved

    def rebase(self) -> dict[int, int]:
        """Rebuild the smoother from its :meth:`content` with one batch iSAM2 update on a fresh ``ISAM2``.

        What follows then depends only on that content and the later calls, so a
        state restored from a stored content plus the journal since (a disk
        snapshot, ``app/disk_snapshots.py``) costs the same at any step. The
        rebuild re-eliminates the whole window at the linearisation point, which
        iSAM2 does only partly (a new Bayes tree and ordering), so estimates
        differ slightly from a smoother that was never re-based. The journal
        restarts with the re-base: no later restore needs what came before it. Returns the map from the old
        factor indices to the new ones (the batch update numbers the content's factors in order).
        """
        graph, values, stamps, moved = self._content()
        if self.journal is not None:
            self.journal = [("rebase", graph, values, stamps)]
        self._rebuild(graph, values, stamps)
        return moved

    def _rebuild(self, graph, values, stamps) -> None:
        gtsam = self._gtsam
        self.isam = gtsam.ISAM2(self.params)
        self.isam.update(graph, values)
        self._stamps, self._keys = [s for s, _ in stamps], [list(k) for _, k in stamps]
        self._stamp_of, self._name_of, self._key_of = {}, {}, {}
        self._groups = gtsam.KeyGroupMap()
        for s, keys in stamps:
            for key in keys:
                name = gtsam.DefaultKeyFormatter(key)
                self._stamp_of[key], self._name_of[key], self._key_of[name] = s, name, key
                self._groups.insert2(key, 1)

    def _insert(self, key: int, stamp: float) -> None:
        if key in self._stamp_of:  # a key given again moves to its new timestamp (gtsam erases the old entry first)
            i = bisect.bisect_left(self._stamps, self._stamp_of[key])
            self._keys[i].remove(key)
            if not self._keys[i]:
                del self._stamps[i], self._keys[i]
        else:
            name = self._gtsam.DefaultKeyFormatter(key)
            self._name_of[key], self._key_of[name] = name, key
            self._groups.insert2(key, 1)
        self._stamp_of[key] = stamp
        if not self._stamps or stamp > self._stamps[-1]:  # the usual case: a newer state
            self._stamps.append(stamp)
            self._keys.append([key])
            return
        i = bisect.bisect_left(self._stamps, stamp)
        if self._stamps[i] == stamp:
            self._keys[i].append(key)  # equal timestamps keep insertion order, as in a std::multimap
        else:
            self._stamps.insert(i, stamp)
            self._keys.insert(i, [key])

    def replay(self, entries) -> None:
        """Make the calls of a :attr:`journal` (graphs and values as gtsam objects) again, in order."""
        for entry in entries:
            if entry[0] == "update":
                self._update(entry[1], entry[2], entry[3], entry[4] if len(entry) > 4 else None,  # a re-base: journalled
                             len(entry) > 5 and entry[5])
            elif entry[0] == "rebase":
                self._rebuild(entry[1], entry[2], entry[3])
            else:
                getattr(self, entry[0])(entry[1])

    # Estimates: the same calls as on gtsam's smoother.
    def calculateEstimatePose3(self, key):
        if self.journal is not None:
            self.journal.append(("calculateEstimatePose3", key))
        return self.isam.calculateEstimatePose3(key)

    def calculateEstimateVector(self, key):
        if self.journal is not None:
            self.journal.append(("calculateEstimateVector", key))
        return self.isam.calculateEstimateVector(key)

    def calculateEstimateConstantBias(self, key):
        if self.journal is not None:
            self.journal.append(("calculateEstimateConstantBias", key))
        return self.isam.calculateEstimateConstantBias(key)

    def marginalCovariance(self, key):
        if self.journal is not None:
            self.journal.append(("marginalCovariance", key))
        return self.isam.marginalCovariance(key)
