-- The spec of a sweep's first job in grid order (the scene the reports share: summary.rs).
-- ?1: sweep id
SELECT j.id, j.spec FROM sweep_points p
JOIN jobs j ON j.id = p.job_id
WHERE p.sweep_id = ?1
ORDER BY p.point, p.replica
LIMIT 1
