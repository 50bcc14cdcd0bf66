-- Every sweep row whose job id starts with a prefix, with its result where there is one (the
-- columns of `sweep_points.sql` and the sweep id): a range of the index on
-- `sweep_points.job_id`, in no particular order (the caller sorts the few rows it finds).
-- ?1: the prefix, ?2: the prefix followed by a character above every hex digit
SELECT p.sweep_id, p.point, p.replica, p.coords, p.job_id, j.status, j.spec, j.attempts,
    j.last_error, r.phase, r.decided_on, r.observables, r.simulated_time,
    r.wall_seconds, r.events, r.finished_at, r.owner AS result_owner, r.trend
FROM sweep_points p
JOIN jobs j ON j.id = p.job_id
LEFT JOIN results r ON r.job_id = p.job_id
WHERE p.job_id >= ?1 AND p.job_id < ?2
