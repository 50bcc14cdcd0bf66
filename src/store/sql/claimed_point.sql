-- The point, replica, coords and sweep name of a claimed job.
-- ?1: sweep id, ?2: job id
SELECT p.point, p.replica, p.coords, s.name
FROM sweep_points p
JOIN sweeps s ON s.id = p.sweep_id
WHERE p.sweep_id = ?1 AND p.job_id = ?2
ORDER BY p.point, p.replica LIMIT 1
