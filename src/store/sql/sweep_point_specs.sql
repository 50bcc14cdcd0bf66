-- Every row of a sweep with its job's spec and no result columns (the line keys of the
-- relabelling).
-- ?1: sweep id
SELECT p.job_id, j.spec
FROM sweep_points p
JOIN jobs j ON j.id = p.job_id
WHERE p.sweep_id = ?1
