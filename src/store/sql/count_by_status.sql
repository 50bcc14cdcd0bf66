-- A sweep's jobs counted by status.
-- ?1: sweep id
SELECT j.status, count(*) FROM sweep_points p JOIN jobs j ON j.id = p.job_id
WHERE p.sweep_id = ?1 GROUP BY j.status
