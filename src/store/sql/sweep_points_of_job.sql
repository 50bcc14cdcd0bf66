-- The rows of one job in a sweep with its result where there is one (the columns of
-- `sweep_points.sql`).
-- ?1: sweep id, ?2: job id
SELECT p.point, p.replica, p.coords, p.job_id, j.status, j.spec, j.attempts,
    j.last_error, r.phase, r.decided_on, r.observables, r.simulated_time,
    r.wall_seconds, r.events, r.finished_at, r.owner AS result_owner, r.trend
FROM sweep_points p
JOIN jobs j ON j.id = p.job_id
LEFT JOIN results r ON r.job_id = p.job_id
WHERE p.sweep_id = ?1 AND p.job_id = ?2
