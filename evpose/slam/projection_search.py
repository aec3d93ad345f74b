"""Re-finding map points by projection: ORB-SLAM's ``SearchLocalPoints`` adapted to MCIs without descriptors.

KLT associations die for good once a track is lost (on a scene with few
corners about two thirds of them per MCI), and a map point without a track is
never seen again, so maps starve. Here the local map's untracked points are
projected with a predicted pose and looked for in the current MCI by
normalised cross-correlation of a small patch cut from the keyframe MCI that
last observed the point; a match must be strong and unique (the second-best
peak, away from the best, clearly weaker). Event images of the same edges
under similar motion look alike up to brightness and contrast, which NCC
ignores; the patch is not warped (the local map spans a few degrees).

Re-associating the first leg's points after the landing's turn (session 21, ``/tmp/s21/revisit9/``, event-only):
points made before 1.5 s (true positions triangulated at the true keyframe poses) that project into the MCI at the
true pose after 2.0 s number 30-46 per MCI (median; seeds 0, 2, 10, 31, 32, 38), the system tracks 0-9 of them among
26-39 tracked points. Given as extra keyframe observations to the local BA at their true pixels + 0.7 px noise
(``oracle.py ba``; map positions as the SLAM has them) they mend the drift: seeds 0-23 1.80 -> 1.27 % (within 2 %
20 -> 23 of 24, better in 24); 10 % of them (about 24 observations a run) within 10 px of the predicted projection,
1 px noise: 1.51 % (21); all of them with 3 px noise, six seeds 3.38 -> 1.38 %. As per-MCI PnP pairs instead they
did not help (six seeds 3.38 -> 2.87 %, map lost on seed 10). No matcher here supplies them: their projection by the
SLAM's pose lies a median 3-8 px off (8-45 % within 3 px); the stored template reaches NCC 0.8 at the true pixel for
18-36 % of the (point, MCI) pairs (median NCC 0.19-0.64), and this module's search (10 px) finds 4.8 % of them right
(within 2 px) and 4.9 % wrong; templates cut from the keyframe MCI through the ground-plane homography at the TRUE
poses did no better (the views differ by only 8-10 deg; ``match.py``): the legs' event images differ, not the
geometry. Searching the old points at each keyframe (``oracle.py ncc``): 1.80 -> 2.00 % (16 of 24 within 2 %),
307 matches in 24 runs, 28 of them within 2 px of the truth; keeping only those (a precision oracle) 1.82 %: the
yield, not only the precision, is some 20 times short.

A geometric association without appearance does not work either (session 21, ``/tmp/s21/fuse9/oracle.py geo``): at each
keyframe after 2.0 s the points last observed before the local window are projected with the keyframe's SLAM pose,
paired with the keyframe's features within 12 px, a 2-D similarity fitted to the pairs by RANSAC (2 px), and each point
given the unique feature within 2 px of its corrected projection (second-nearest >= 4 px) as a local-BA observation.
Seeds 0-23: 1.80 -> 1.83 % (paired +0.04 +- 0.10, better 10, worse 14; within 2 % 20 -> 17), 2.0 associations per
keyframe (260 keyframes), 40 of the 344 with a true position within 2 px of it (median 6.0 px off); the six hard seeds'
3.38 -> 2.71 % (5 of 6 better) did not carry over. Two reasons, both measured: (1) the keyframe's features are not
where the old points are: a feature lies within 1 / 2 / 3 px of an old point's true pixel for 3 / 10 / 19 % of the
5330 (point, keyframe) pairs; (2) the projection error is not a smooth field: the best 2-D model fitted by least
squares to the TRUE pixels leaves a median 2.2-6.9 px (shift), 2.2-5.7 (similarity), 1.7-4.4 (affine, 23-55 % within
2 px), 1.8-5.1 (homography) of the raw 3.0-8.8 px (seeds 0, 2, 10, 31, 32, 38): the old points' own map positions
are off, point by point. The RANSAC model fitted to the feature pairs fits chance coincidences (median 8 inliers) and
leaves the projections no nearer the truth (similarity, seeds 10 / 0 / 2: 8.8 -> 9.1, 3.0 -> 7.4, 6.2 -> 9.2 px;
shift 8.7 -> 7.0, 2.9 -> 7.0, 6.2 -> 6.4; homography 13-25 px).

A binary descriptor does not supply them either (session 21, ``/tmp/s21/desc9/desc.py``; seeds 0-7, 10, 31, 32, 38:
4425 (old point, post-turn keyframe MCI) pairs over 151 keyframes). OpenCV ORB (upright, one level, 31 or 15 px patch)
at the point's pixel in its last first-leg keyframe MCI, best Hamming match with a ratio test over every pixel (or
FAST corner) within 10-15 px of the projection by the SLAM's pose, on the raw MCI, blurred (sigma 1.5) or its
gradient magnitude, optionally with a mutual back-search: the descriptor at the true pixel differs from the source by
a median 74-83 of 256 bits; best precision 35 % (15 px, at most 48 bits, ratio 0.7, mutual: 4.0 % of pairs right,
7.2 % wrong, 1.2 right per keyframe); three right per keyframe only at 23 % precision (10 wrong per keyframe). This
module's NCC search on the same pairs: 3.7 % right, 4.2 % wrong (47 %). Within the first leg (sources at least 0.3 s
older) ORB's 31 px patch reaches 75 % precision at 4.1 % right; after the turn 25 %: a change of motion direction
breaks descriptors as it breaks templates. Untried then (both tried since, below): a matcher learnt on MCIs of both
motion directions (session 23), or the first leg rendered as the new motion would show it (the event set itself
carries the old motion's direction, so re-warping the old events is not enough: a log-intensity map integrated from
them with their known flow, differentiated along the new motion; session 22).

Rendering the first leg as the new motion would show it does not supply them either (session 22, ``/tmp/s22/render9/``:
``capture.py`` runs the defaults keeping every keyframe's MCI, its signed twin and the map, ``oracle.py`` /
``render.py`` match; seeds 0, 2, 10, 31, 32, 38, 1368 (old point, keyframe after 2.0 s) pairs over 76 keyframes, an old
point having at least two keyframe observations, all before 1.6 s, triangulated at the true poses within 3 px; the truth
is the source observation carried to the keyframe by the true poses at the point's depth; search 12 px around the
projection by the keyframe's PnP pose, NCC >= 0.8, uniqueness 0.9, right within 2 px). 11 px templates: plain 0.11 right
per keyframe at 16 % precision (NCC at the truth, best within 2 px: median 0.42, 25 % >= 0.8); (a) the source MCI
reweighted by ``sqrt(v_new' J v_new / v_old' J v_old)`` (``J`` its structure tensor, ``v`` the true flow directions at
the point) 0.03 at 3 %; (b) the signed (ON - OFF) source patch integrated along ``v_old`` and differentiated along
``v_new`` 0.00 (NCC median 0.32: streaks along ``v_old``); as source the first-leg keyframe whose true flow direction at
the point is nearest the new one (over the first leg it turns a median 64-82 deg at a point, and comes within a median
4-11 deg of the new direction; seeds 0, 2, 10) 0.04 at 5 %, among the keyframes that observed the point 0.09 at 12 %.
The premise does not hold: NCC at the truth does not depend on how far the flow direction turned between source and
keyframe (post-turn pairs in 15 deg bins from 0 to 90 deg: median 0.35 / 0.52 / 0.39 / 0.31 / 0.40 / 0.51), and old
points are as hard to re-find within the first leg (``CONTROL=1``: keyframes 0.9-1.6 s, sources >= 0.3 s older; seeds 0,
2, 10, 10 px: median 0.44, 28 % >= 0.8, 13-15 % precision). What limits the search is the aperture: the templates are
edge segments (structure-tensor coherence median 0.96 for those matching at the truth), and of the 342 pairs whose
template reaches 0.8 at the truth the best peak within 12 px lies elsewhere for 287; 9 are right and unique
(``diag.py``). Wide templates warped into the new view (31 px, plane at the point facing the new camera, the SLAM's
poses) do better: 0.33 right per keyframe at 47 % (NCC 0.8), 0.50 at 37 % (0.6); at the true poses 0.34 at 44 %;
reweighted (a) on top 0.33 at 48 %; unwarped 31 px 0.01 at 4 %, warped 11 px 0.04 at 6 %. Wired as a search of the
points last observed before the local window at each new keyframe (event-only, matches as keyframe observations before
the local BA; ``revisit_search.py``, commit 9a820a3,
removed by the next), 31 px, 12 px radius: seeds 0-23 1.80 -> 1.85 % (within 2 % 20 -> 18), paired +0.05
+- 0.21 (better 14; 10: 4.58 -> 2.32, 13: 2.11 -> 1.11, but 5: 1.41 -> 4.89, 19: 1.86 -> 3.25, 12: 1.46 -> 2.69), 111
matches in 24 runs, 33 within 2 px of the point's truth (``insitu.py``); NCC 0.7: 1.85 % (18), +0.06 +- 0.19, 200
matches, 51 right; seeds 24-35 (31 px) 2.23 -> 2.19 % (8 -> 8), -0.04 +- 0.29, 73 matches, 12 right. Four to eight
matches a run, a third of them right, reshuffle the runs after the turn; the session-21 oracle that helped gave about 24
right observations a run.

The revisit matches as 1-D observations across the template's edge do not help either (session 23, ``/tmp/s23/edge9/``:
``edge_oracle.py`` on render9's captures and pairs, ``insitu1d.py``, ``oracle1d.py``, ``exp.py`` runs; code in commit
afae798 on top of 9a820a3's search, both reverted by the next). A template of an edge matches anywhere along it, and
the old points' error after the turn does lie mostly across their edges (the projection by the keyframe's PnP pose is a
median 4.6 px off across the warped 31 px template's edge, 3.3 px along it; 1124 pairs over 76 keyframes, seeds 0, 2,
10, 31, 32, 38, truth as render9's), so a match was tried as an observation only across the edge: normal from the warped
template's structure tensor (Gaussian 3 px about its centre), uniqueness asked only of peaks more than 2 px across it,
a local-BA factor with sigma 1 px across and 10 px along (``revisit_along_sigma_px``; kept apart from the 2-D ``obs``,
which culling, templates and KLT read). Oracle (NCC 0.8, 12 px): 4.80 matches per keyframe, 1.95 right across within
1 px (41 %), 2.99 within 2 px (62 %), median 1.40 px across and 5.1 along, against render9's 2-D search's 0.30 right
within 2 px at 45 % here (0.26 within 1 px across, 39 %) and the projection's own 13 / 25 % within 1 / 2 px across on
the same pairs; no uniqueness test 2.18 (39 %) / 3.36 (60 %); stricter NCC (0.85-0.95) or uniqueness (0.7-0.8) leave
the precision at 34-38 % within 1 px; the straightest templates (coherence >= 0.9) 33 %; 11 px templates 2.01 at 34 %;
the triangulated truth 37 %. By the true new flow at the point: where it runs within 20 deg of the edge (the
hypothesis's case, the old edge across its birth flow) 51 of 309 pairs match, 55 % within 1 px and 80 % within 2 px;
20-45 deg 45 / 65 %; beyond 45 deg 36 / 58 % (245 of 621). So the yield rose sixfold, the precision did not. In situ
(landing seeds 0-23 against the defaults' 1.80 %, 20 within 2 %): all matches, 2.24 % (12; paired +0.45 +- 0.18 points,
better 7; 0: 1.79 -> 4.05, 12: 1.46 -> 4.58, 10: 4.58 -> 3.54), 78-139 matches a run right across within 1 / 2 px for
26 / 43 % against the projection's own 20 / 37 % (seeds 0, 2, 4, 10, 11, 12; in the oracle's population 32 / 51 % against
25 / 46 %); only where the flow predicted by the last two keyframes' poses runs within 20 deg of the edge
(``revisit_max_flow_across`` 0.34), 2.11 % (19; +0.31 +- 0.24, better 10; 9: 2.38 -> 7.06, 20: 1.59 -> 3.96), 15-21
matches a run, 22 / 43 % right against the projection's 23 / 38 %. Nor would a better matcher do much: the true pixels
(+ 0.7 px per axis) as 1-D observations (template normal, 1 / 10 px) of every first-leg point (all observations before
1.6 s, consistent within 3 px) at every keyframe after 2.0 s give 1.60 % (21 within 2 %, median 1.35; -0.20 +- 0.19,
better 18, but 20: 1.59 -> 4.50, 17: 1.86 -> 2.88), 158 observations a run; as 2-D observations (joining ``obs``, so a
point leaves the revisit set after its first: 31 a run) 1.46 % (23; -0.34 +- 0.13). Across the edge alone the old points
pin the new keyframes less than the 2-D oracle does, and the matches found in situ are hardly nearer the truth across
the edge than the projection they start from.

A matcher learnt on MCIs of both motion directions does not supply them either (session 23, learn9: scripts and logs in
commit 6098c3f, ``experiments/s23_learn9/``, reverted by the next; ``feats.py``, ``learn.py``, ``rank.py``,
``metric.py``; numpy / scipy only). Training pairs from seeds 40-75 (``capture.py`` at the defaults, render9's pair
rules: 9079 pairs over 451 keyframes), test pairs render9's (seeds 0, 2, 10, 31, 32, 38: 1350 of its 1368 pairs, 76
keyframes), warped 31 px templates (SLAM poses), search 12 px around the projection by the keyframe's PnP pose, right
within 2 px; truth render9's (the source observation carried by the true poses; in brackets the triangulated point's
projection, 0.78 px median apart). Per search position, score maps of the template against the keyframe MCI: NCC at 11 /
21 / 31 / 41 / 51 px, blurred, polarity-free gradient orientation (doubled angle, 15 / 31 px), gradient magnitude, the
signed (ON - OFF) twin, nine 11 px cells of the template (raw and orientation: a learnt spatial weighting), the distance
from the projection; combined by a logistic regression (positives within 1 px, negatives beyond 2 px: the ten
highest-NCC, i.e. along the edge, and twenty at random) or a conditional logit (softmax over the window); the peak then
verified by a logistic regression or boosted stumps on its scores, its uniqueness, the elongation of its ridge, the
template's coherence and self-similarity. Render9's NCC search (0.8): 0.33 right per keyframe at 47 % (0.29 at 42 %).
The peak is right for 10 % of the pairs by NCC 31 px (98 of the 957 peaks not on the window's border), 7 % by the
logistic score, 11 % by the conditional logit (1.92 per keyframe). Thresholding the verifier, right per keyframe at
precision: conditional logit + boosted stumps 1.25 at 35 %, 0.75 at 42 %, 0.55 at 44 %, 0.36 at 50 % (1.17 at 33 %, 0.86
at 48 %, 0.54 at 60 %, 0.46 at 65 %, 0.25 at 70 %); NCC peak + boosted stumps 0.54 at 42 %, 0.37 at 58 %, 0.28 at 72 %,
0.25 at 79 % (by the logistic verifier 0.57 at 45 %, 0.32 at 62 %, 0.18 at 70 %); further asking that the same point's
peak at a keyframe at most two away lie within 1 px of the same offset from its projection 0.57 at 41 %, 0.26 at 61 %
(0.53 at 54 %, 0.21 at 76 %): a wrong peak slides along its edge as consistently as a right one stays. Training on seeds
40-55 only (3856 pairs) gave curves within about ten points of these (0.58 at 46 %, 0.55 at 62 %): more data do not lift
them. A Mahalanobis metric on normalised patches (KISSME on PCA-reduced differences of blurred 16 x 16 samplings of
template and target patch, 30 or 80 dimensions, seeds 40-55) does worse than NCC (peaks right 6-7 %, at best 0.20 per
keyframe at 30 %). Nothing reaches 75 % at 0.5 right per keyframe (the best at 0.5 is 44 %, 60 % by the point's truth),
so it was not wired in (matches at 40-47 % precision hurt, above). Why: the truth is not distinctive in any compared
channel. Of the median 612 positions in the window more than 2 px from the truth, a median 102 score above the best
position within 1 px of it by NCC 31 px (the truth best in 5 % of the pairs), 67 by orientation (6 %), 90 by 51 px NCC
(7 %), 240 by the signed twin, 53 by the conditional logit (7 %), 124 by the metric (4 %): learning halves the
competitors, it leaves dozens.

What a matcher would need (session 23, need9: ``need.py``, ``table.py`` and the runs' logs in commit cb4628e,
``experiments/s23_need9/``, reverted by the next; run on edge9's code, 61fbdfa + afae798 cherry-picked as 1612de5 +
8b708ec, also reverted). The 2-D oracle above (first-leg points, all observations before 1.6 s, consistent within 3 px,
true pixel + 0.7 px per axis, local-BA keyframe observations at keyframes after 2.0 s; 1.458 %, reproduced bit for bit)
degraded by two knobs: each (point, keyframe) candidate kept with probability Q (yield; a point left out may be kept at
a later keyframe, a kept one joins ``obs`` and leaves the set, so Q = 1 gives 31 a run, 2.67 per post-2.0 s keyframe; at
Q 0.05 a keyframe has 13.6 candidates, render9's 18 pairs) and, if kept, wrong with probability 1 - P
(precision): the true pixel displaced 3-10 px either way ALONG the edge (minor eigenvector of the warped 31 px
template's structure tensor, ``edge_normal``; the aperture failure of the matchers above), or in a random direction
(``any``), or put at the projection by the keyframe's SLAM pose (``pred``: a match confirming the drift). Landing seeds
0-23 against the defaults' 1.80 % (median 1.54, 20 within 2 %), paired per seed (better / worse):

    Q     P     wrong  right / wrong per kf  obs a run  mean ATE  median  within 2 %  paired           better/worse
    1     1     -      2.67 / 0              31         1.46 %    1.44    23          -0.34 +- 0.13    18 / 6
    1     0.8   edge   2.16 / 0.54           31         1.49      1.43    23          -0.31 +- 0.14    19 / 5
    1     0.6   edge   1.62 / 1.03           31         1.67      1.54    19          -0.13 +- 0.10    18 / 6
    1     0.6   edge   (another draw)        31         1.60      1.40    21          -0.20 +- 0.17    17 / 7
    1     0.6   any    1.61 / 1.04           31         1.59      1.49    21          -0.21 +- 0.16    15 / 9
    1     0.6   pred   1.61 / 1.03           31         1.68      1.51    20          -0.12 +- 0.06    16 / 8
    1     0.8   pred   2.12 / 0.53           31         1.85      1.50    18          +0.05 +- 0.14    14 / 10
    1     0.45  edge   1.20 / 1.43           31         1.64      1.41    21          -0.15 +- 0.20    17 / 7
    0.25  1     -      1.95 / 0              23         1.66      1.46    21          -0.14 +- 0.21    19 / 5
    0.25  0.75  edge   1.41 / 0.52           23         1.58      1.42    22          -0.22 +- 0.16    20 / 4
    0.1   1     -      1.15 / 0              14         1.57      1.49    20          -0.23 +- 0.11    19 / 5
    0.1   0.75  edge   0.87 / 0.29           14         1.80      1.64    19          +0.00 +- 0.08    15 / 9
    0.05  1     -      0.67 / 0              8          1.57      1.47    22          -0.22 +- 0.10    19 / 5
    0.05  0.75  edge   0.51 / 0.16           8          1.72      1.57    21          -0.07 +- 0.18    18 / 6
    0.05  0.45  edge   0.31 / 0.36           8          1.78      1.61    20          -0.02 +- 0.18    14 / 10
    0.05  0.45  pred   0.30 / 0.36           8          1.70      1.59    21          -0.10 +- 0.09    16 / 8
Single runs are chaotic: one or two seeds a run jump to 2.7-5.1 % (e.g. 14: 1.73 -> 5.12 at Q 0.25, P 1), another draw
of which observations are wrong moved the mean by 0.08 points, so differences under about 0.15 points between rows mean
nothing; seed 10 (4.58 %) is mended to 1.3-1.7 % by most rows at Q >= 0.25 (3.5-3.9 by three), to 2.1-2.6 at Q <= 0.1
(4.4 by one). So: yield is not what limits -- eight right observations a run (0.67 per post-turn keyframe, Q 0.05) mend
as much as 14-23 (-0.22 +- 0.10, 19 of 24 better; the four P = 1 rows average -0.23) -- precision is. Wrong observations
displaced 3-10 px along the edge or in any direction do not make things worse than the defaults at any rate tried, but
they eat the gain: the rows at P 0.75-0.8 average -0.15, at P 0.45-0.6 -0.13 (from +0.00 to -0.31 and -0.02 to -0.21:
single rows differ by as much as the chaos, so only these averages read), and at the in-situ matchers' rate (eight a
run, 0.3 right per keyframe at 45 %) the result is neutral (1.78 %). Wrong ones at the SLAM's own projection are the one
kind that can cancel all of it (-0.12 at P 0.6 but +0.05 at P 0.8, seed 10 left at 3.90 %, 4: 2.41 -> 3.85, 14: 1.73 ->
4.19; they pull the keyframes toward the drift the right ones correct). Target for a matcher to beat 1.80 % clearly
(about -0.2 points, two s.e.): about 0.7 right observations per post-turn keyframe (8 a run) at 90-100 % precision, or
the full 2-3 per keyframe at 80 %; at 75 % or below the expected gain is about -0.1 +- 0.15, i.e. invisible in 24 seeds.
The best real ones reach 0.3-0.5 right per keyframe at 40-60 %, short by a factor of about two in precision. Yet in situ
such matches HURT (1.85-2.24 %) where this model at their rate is neutral: their errors must be worse than modelled
(untested which way: "right" matches up to 2 px off, not 0.7 px; wrong ones farther than 10 px, near the drifted
projection (the ``pred`` rows) or correlated across the keyframe; made for any point last observed before the local
window, not only the consistent first-leg points the oracle draws from). Untried: measure the in-situ matches' error
distribution and population against this model before building another matcher.

The in-situ matches' errors are worse than that model in four of the five ways (session 23, err9: ``record.py``,
``analyse.py`` and logs in commit 8d78c8b, ``experiments/s23_err9/``, run on main f82efc6 + 9a820a3 cherry-picked as
65a1e68, both reverted by the next). Render9's 2-D search as it ran (31 px warped templates, 12 px, NCC 0.8; its in-situ
ATEs reproduced: 10: 2.317 %, 12: 2.694 %), every accepted match logged with the point's truth (triangulated at the true
poses of its earlier observations, projected at the keyframe's true pose, as ``insitu.py`` / ``need.py``), the
projection by the keyframe's SLAM pose (the search's centre) and the warped template's edge (edge9's structure tensor).
Landing seeds 0-23 (in brackets seeds 0, 2, 4, 10, 11, 12, 26 matches): 111 matches, 4.6 a run (not the model's 8),
22 of them at keyframes before 2.0 s (outside the oracle's window); within 1 / 2 / 3 px of the truth 6 / 30 / 42 %,
median 3.6 px (4 / 19 / 35 %, 4.4 px), against the projections they started from 5 / 16 / 32 %, 4.2 px. So the
precision is 30 %, not the 45 % modelled, and (1) the "right" ones are a median 1.42 px off (6 % of all within 1 px),
not the model's 0.82 (0.7 px per axis). (2) The wrong ones (78): median 4.8 px, quartiles 3.5 / 8.7, 18 % beyond 10 px
(33 %), up to 35 px; (3) not mainly along the edge as modelled: median 40 deg from it, 34 within 30 deg of along, 30
beyond 60 deg (across 2.6, along 3.0 px median). (4) Not pulled to the drift: 21 of 78 lie nearer the SLAM's projection
than the truth does, 5 within 2 px of it, the cosine of the match's error with the projection's error a median 0.12
(0.70 over the six seeds' 21; the right ones 0.06): not the ``pred`` rows' failure. (5) Correlated within a keyframe:
84 keyframes have matches (63 one, 17 two, 2 three, 2 four); over the 35 same-keyframe pairs the error vectors'
cosine is a median 0.64, and over the 16 pairs both wrong 0.97 (11 above 0.7), nearly all neighbouring points 2.6-7 px apart
(seeds 14, 19, 23) matched to one wrong place by one shared offset -- one error counted up to four times (seed 19, 12
matches: 1.86 -> 3.25 %). (6) Population: 82 of the 111 are need9's first-leg points (all observations before 1.6 s,
consistent within 3 px; no old point last seen before 1.6 s was inconsistent), 37 % right (60 at post-2.0 s keyframes,
40 %, median 2.65 px); the other 29 are points last observed at 1.6 s or later (during the turn), 10 % right, median
5.6 px. Hence need9's candidate reasons: right matches 2 px rather than 0.7 px off, wrong ones beyond 10 px (a fifth),
correlated within a keyframe, and matches of points seen during the turn all hold; the pull towards the drifted
projection does not. The precision in the oracle's own population and window (40 %, 1 a run) is near the model's 45 %
row; the 22 pre-2.0 s matches, the 29 turn-time points at 10 % and the clusters of neighbours sharing one wrong offset
are what the model lacked. Untried: the model re-run with these recorded error vectors, and the search restricted to
first-leg points at post-2.0 s keyframes with one match per 8 px neighbourhood (at 40 % precision it would still be
short of the 80-90 % a clear gain needs).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import cv2
import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import SlamMap
from evpose.slam.geometry import project


class SearchMatcher(str, enum.Enum):
    """How an untracked local-map point is looked for near its projection."""

    NCC = "ncc"
    """Normalised cross-correlation of a template cut from the point's newest keyframe MCI."""
    KLT = "klt"
    """Pyramidal KLT from the point's newest keyframe observation in that keyframe's MCI (:mod:`evpose.slam.keyframe_search`)."""


@dataclass
class ProjectionSearchConfig:
    """Search of untracked local-map points around their projection in the current MCI (NCC patches or KLT)."""

    enabled: bool = True
    """Re-find local-map points by projection (off: associations come from KLT tracks only). With the NCC matcher it
    lowered the scale-aligned ATE on two of the simulated landing seeds 0-3 (event-only) and raised it on two; with the
    KLT matcher see ``matcher``."""
    event_inertial: bool = False
    """Search in event-inertial mode too. Off: on landing seeds 0-7 (E-I-C2, 3 s) the KLT matcher lowered the mean ATE
    from 3.71 % to 2.31 % but raised the median from 1.71 % to 2.04 % and the worst RPE from 0.0091 to 0.0118 m/m and
    from 0.0057 to 0.0068 deg/m."""
    matcher: SearchMatcher = SearchMatcher.KLT
    """How points are matched (with KLT the radii below bound how far a match may land from the projection). On the
    simulated landing (event-only, 3 s, seeds 0-23) KLT lowered the scale-aligned ATE from a mean of 3.20 % (median
    2.67, worst 9.32, 2 seeds <= 2 %) without search to 2.63 % (median 2.53, worst 5.77, 8 seeds <= 2 %), better on 15
    seeds and worse on 9, at 93.9-99.0 % tracked (before 95.4-99.0 %) and a median CPU per MCI of 19.5 ms (before
    10.9); NCC gave 3.09 % (median 2.73, 3 seeds <= 2 %). The gain is fragile: with ``reprojection_threshold_px`` 2.4
    instead of 2.5 the same comparison went from 3.78 % to 4.14 % (median 2.73 -> 4.20), with ``ba_huber_px`` 1.9 from
    3.70 % to 2.96 % (median 2.70 -> 2.28)."""
    klt_keyframes: int = field(default=0, metadata={"min": 0, "max": 30, "step": 1, "unit": "keyframes"})
    """KLT matcher: the newest this many keyframes of the local window are source views, tried newest first until the
    point is found (0: all of them; an edge's events depend on the motion, so an older view may look more like the
    current MCI). On landing seeds 0-23 (event-only) all gave a mean ATE of 2.63 % (median 2.53), 3 gave 3.07 %
    (median 2.93), 1 3.03 % (median 2.50), keyframes. Searching the points of the newest 12 / 15 keyframes instead of
    ``TrackingConfig.local_window`` (their MCIs kept as sources; session 11, landing seeds 0-11, 60 runs with
    ``MciConfig.reference_fraction`` 1.0): mean ATE 3.34 -> 3.06 / 3.32 %, 9 -> 13 / 10 of 60 within 2 %, paired
    -0.28 +- 0.21 points (12), at 4-8 ms more CPU per MCI; not kept. Session 19 (``/tmp/s19/turn9/``, against
    defaults 1.82 %, 19 of 24 within 2 %): the points of the newest 40 keyframes (every point of a 3 s landing map;
    40-55 untracked points of keyframes older than ``local_window`` project into each MCI after the turn, against about
    20 tracked) -> seeds 0-23 2.09 % (17 within 2 %), paired +0.26 +- 0.23, CPU per MCI 25.4 -> 32.4 ms median; the
    newest 12 -> 2.14 % (17), +0.32 +- 0.22, 28.3 ms; both turned the same four seeds (4, 14, 15, 19: 1.7-2.5 %) into
    4.1-4.9 % runs; the newest 4 -> 2.32 % (12), +0.50 +- 0.25, 21.2 ms; not kept."""
    fuse_radius_px: float = field(default=0.0, metadata={"min": 0.0, "max": 10.0, "step": 0.1, "unit": "px"})
    """Event-only: after each pose estimate, live tracks without a map point take over an untracked map point projecting
    within this distance, when the pair is unambiguous (:mod:`evpose.slam.track_fusion`; 0: off), pixels. Session 19
    (``/tmp/s19/turn9/``, landing event-only 3 s, against defaults): 1.5 -> seeds 0-23 1.82 -> 1.63 % (within 2 %
    19 -> 20, worst 4.58 -> 2.65), 24-47 2.86 -> 2.73 % (14 -> 15), 48-71 2.51 -> 2.57 % (13 -> 13); the 72 runs paired
    -0.09 +- 0.14 points (better in 40); the runs failing after the turn (10, 31, 32, 37, 38: 3.8-4.7 %) all came to
    1.35-2.06 %, others failed instead (43, 44, 52, 66: 4.6-5.1 %), the first-leg collapses (27, 36, 60, 67) stayed.
    On seeds 0-23 the summed keyframe-to-keyframe x-rotation error fell from 7.0 to 6.1 deg (mean), the RMS keyframe
    rotation error from 1.40 to 1.30 deg, the median PnP inliers after 2 s rose from 34.2 to 36.6. With
    ``TrackingConfig.ba_huber_px`` 1.9 (seeds 0-47) -0.21 +- 0.20, seeds 48-71 -0.11 +- 0.21, with 2.1 (seeds 0-47)
    +0.17 +- 0.21: the 192 runs 2.36 -> 2.31 % (median 1.78 -> 1.71, within 2 % 116 -> 118), paired -0.05 +- 0.09
    (better in 103). Radius 1.0 / 2.5 on seeds 0-23: 1.96 / 2.07 %
    (+0.13 +- 0.19 / +0.25 +- 0.20); also giving the point the new track's observations in earlier keyframes (within
    5 px): 1.91 % (+0.09 +- 0.19). Indoor seeds 0-7 with 1.5: 6.83 -> 6.84 %, from the events 40.7 -> 39.6 %. Within
    the noise: off. CPU per MCI unchanged (landing median 23-25 ms)."""
    patch_px: int = field(default=11, metadata={"min": 5, "max": 31, "step": 2, "unit": "px"})
    """Side of the template cut around a point's observation in its keyframe MCI, pixels (odd)."""
    radius_px: int = field(default=6, metadata={"min": 1, "max": 30, "step": 1, "unit": "px"})
    """Search radius around the projection with the motion-model pose (before pose estimation), pixels."""
    prepass_below: int = field(default=0, metadata={"min": 0, "max": 1000, "step": 1, "unit": "points"})
    """The first pass (motion-model pose, wide radius) runs only while KLT carries fewer map points than this; the second
    pass (estimated pose) always runs. 0 by default: as a rescue of a failing KLT step the first pass "re-found" points of
    an unrelated scene among look-alike blobs and kept a map that should have been lost, points. Session 40
    (``/tmp/s40/cv40``, README.txt there): 12, indoor event-only seeds 0-9 against main's defaults: more time from the
    events (28.0 -> 34.6 % mean; seeds 1, 3, 4: 31 -> 46, 23 -> 39, 24 -> 41 %) but a worse scale-aligned ATE
    (1.96 -> 2.26 %, paired +0.30 +- 0.14 points; within target 8 -> 4 of 10): the maps it keeps are the small young
    ones, which drift. An oracle KLT search at the true pose finds >= 12 points in only 0.7 % of the indoor coasted
    MCIs (1.3 % at the coast pose), seeds 0-7: in 87 % fewer than 12 of the map's points are in view at all."""
    refine_radius_px: int = field(default=3, metadata={"min": 1, "max": 15, "step": 1, "unit": "px"})
    """Search radius around the projection with the estimated pose (second pass), pixels. KLT matcher on landing seeds
    0-23 (event-only): 3 px gave a mean ATE of 2.63 % (median 2.53), 5 px 3.22 % (median 2.34)."""
    min_ncc: float = field(default=0.8, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "NCC"})
    """Smallest normalised cross-correlation accepted as a match, NCC."""
    max_second_ratio: float = field(default=0.9, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "ratio"})
    """The best peak outside two pixels of the best match must score below this share of the best (uniqueness), ratio."""
    min_texture: float = field(default=4.0, metadata={"min": 0.0, "max": 64.0, "step": 0.5, "unit": "grey levels"})
    """Templates with a lower standard deviation are not searched (a blank patch matches anything), grey levels."""


def cut_patch(img8: np.ndarray, uv: np.ndarray, size: int) -> np.ndarray | None:
    """The ``size`` x ``size`` patch of ``img8`` centred on ``uv`` (sub-pixel, bilinear), or None when it leaves the image."""
    h, w = img8.shape
    r = size // 2
    u, v = float(uv[0]), float(uv[1])
    if not (r <= u < w - r - 1 and r <= v < h - r - 1):
        return None
    return cv2.getRectSubPix(img8, (size, size), (u, v))


def search_patch(img8: np.ndarray, patch: np.ndarray, uv: np.ndarray, radius: int, cfg: ProjectionSearchConfig) -> tuple[np.ndarray | None, float]:
    """Where ``patch`` matches ``img8`` within ``radius`` px of ``uv``: (sub-pixel position or None, best NCC)."""
    size = patch.shape[0]
    r = size // 2
    h, w = img8.shape
    cu, cv_ = int(round(float(uv[0]))), int(round(float(uv[1])))
    x0, x1 = max(cu - radius - r, 0), min(cu + radius + r + 1, w)
    y0, y1 = max(cv_ - radius - r, 0), min(cv_ + radius + r + 1, h)
    if x1 - x0 < size + 2 or y1 - y0 < size + 2:
        return None, float("nan")
    region = img8[y0:y1, x0:x1]
    if float(cv2.meanStdDev(region)[1][0, 0]) < cfg.min_texture:
        return None, float("nan")
    score = cv2.matchTemplate(region, patch, cv2.TM_CCOEFF_NORMED)
    # NaN where the region is flat under the template.
    cv2.patchNaNs(score, -1.0)
    iy, ix = np.unravel_index(int(np.argmax(score)), score.shape)
    best = float(score[iy, ix])
    if best < cfg.min_ncc:
        return None, best
    if not (0 < iy < score.shape[0] - 1 and 0 < ix < score.shape[1] - 1):
        return None, best  # the maximum on the search border is the flank of something outside the radius, not a peak
    away = score.copy()
    away[max(iy - 2, 0):iy + 3, max(ix - 2, 0):ix + 3] = -1.0
    if away.size and float(away.max()) >= cfg.max_second_ratio * best:
        return None, best
    # Sub-pixel peak by a parabola through the neighbours on each axis.
    du = _parabola(score, iy, ix, axis=1)
    dv = _parabola(score, iy, ix, axis=0)
    return np.array([x0 + ix + r + du, y0 + iy + r + dv]), best


def _parabola(score: np.ndarray, iy: int, ix: int, axis: int) -> float:
    i, n = (ix, score.shape[1]) if axis == 1 else (iy, score.shape[0])
    if i <= 0 or i >= n - 1:
        return 0.0
    a, b, c = (score[iy, i - 1], score[iy, i], score[iy, i + 1]) if axis == 1 else (score[i - 1, ix], score[i, ix], score[i + 1, ix])
    den = a - 2.0 * b + c
    return float(np.clip(0.5 * (a - c) / den, -0.5, 0.5)) if den < 0 else 0.0


def search_by_projection(img8: np.ndarray, K: np.ndarray, T_cw: np.ndarray, Xw: np.ndarray, patches: list[np.ndarray],
                         radius: int, cfg: ProjectionSearchConfig, border: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Look for each point ``Xw[i]`` (with template ``patches[i]``) near its projection by ``T_cw``.

    Returns (indices of the found points (M,), their pixels (M, 2)), in index order.
    Two points claiming pixels closer than 2 px to each other are both dropped: one of them is wrong.
    """
    if len(Xw) == 0:
        return np.zeros(0, np.int64), np.zeros((0, 2))
    h, w = img8.shape
    proj, z = project(K, T_cw, np.asarray(Xw, np.float64))
    b = max(border, patches[0].shape[0] // 2 if patches else 0)
    inside = (z > 0) & (proj[:, 0] >= b) & (proj[:, 0] < w - b) & (proj[:, 1] >= b) & (proj[:, 1] < h - b)
    idx, uv = [], []
    for i in np.flatnonzero(inside):
        found, _ = search_patch(img8, patches[i], proj[i], radius, cfg)
        if found is not None:
            idx.append(int(i))
            uv.append(found)
    if not idx:
        return np.zeros(0, np.int64), np.zeros((0, 2))
    idx_a, uv_a = np.array(idx, np.int64), np.array(uv)
    d = np.linalg.norm(uv_a[:, None] - uv_a[None], axis=2) + np.eye(len(uv_a)) * 1e9
    unique = d.min(axis=1) >= 2.0
    return idx_a[unique], uv_a[unique]


def local_candidates(m: SlamMap, tracked_pids: set[int], window: int) -> list[int]:
    """Ids (ascending) of points seen by the last ``window`` keyframes, with a template, not tracked now."""
    if not m.keyframes:
        return []
    first = m.keyframes[-window:][0].id  # keyframe ids grow, so "seen by a recent keyframe" is "newest observation >= first"
    return [pid for pid, p in sorted(m.points.items()) if p.patch is not None and pid not in tracked_pids and p.obs and max(p.obs) >= first]


def refind_points(m: SlamMap, img8: np.ndarray, K: np.ndarray, T_wc: np.ndarray, tracked_pids: set[int], occupied_uv: np.ndarray,
                  window: int, radius: int, cfg: ProjectionSearchConfig) -> tuple[list[int], np.ndarray]:
    """Untracked local-map points of ``m`` re-found in ``img8`` near their projection by ``T_wc``: (point ids, pixels (M, 2)).

    Matches within 2 px of ``occupied_uv`` (pixels of points tracked already) are dropped as conflicts.
    """
    pids = local_candidates(m, tracked_pids, window)
    if not pids:
        return [], np.zeros((0, 2))
    Xw = np.stack([m.points[p].xyz for p in pids])
    idx, uv = search_by_projection(img8, K, invert_pose(T_wc), Xw, [m.points[p].patch for p in pids], radius, cfg)
    if len(idx) and len(occupied_uv):
        d = np.linalg.norm(uv[:, None] - np.asarray(occupied_uv, np.float64)[None], axis=2).min(axis=1)
        idx, uv = idx[d >= 2.0], uv[d >= 2.0]
    return [pids[i] for i in idx.tolist()], uv


def store_patches(m: SlamMap, kf_id: int, img8: np.ndarray, size: int) -> None:
    """Give every point observed in keyframe ``kf_id`` the template around that observation (the newest view wins)."""
    for p in m.points.values():
        uv = p.obs.get(kf_id)
        if uv is not None:
            patch = cut_patch(img8, uv, size)
            if patch is not None:
                p.patch = patch
