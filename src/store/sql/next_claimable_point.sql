-- The next claimable row of a sweep's queue: its job, point, replica, coords and the sweep's
-- name. Order: jobs that a pending continuation job waits for (a chain's next link) first
-- (claim_rank 0), so chains start and advance as early as possible; then grid order. One walk
-- of the partial index sweep_points_claim to its first row (migration 20261127000000).
-- ?1: sweep id
SELECT p.job_id, p.point, p.replica, p.coords, s.name
FROM sweep_points p
JOIN sweeps s ON s.id = p.sweep_id
WHERE p.sweep_id = ?1 AND p.claim_rank IS NOT NULL
ORDER BY p.claim_rank, p.point, p.replica
LIMIT 1
