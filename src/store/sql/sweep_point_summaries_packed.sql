-- `sweep_point_summaries.sql` without the specs, packed into one JSON array of one array per
-- job (the columns in that statement's order, `coords` as JSON): one row for the whole sweep,
-- so that 10^5 jobs are not 10^5 rows handed one by one from SQLite to the caller (each with
-- a copy of every value). The caller sorts by (point, replica).
-- ?1: sweep id
SELECT json_group_array(json_array(p.point, p.replica, json(p.coords), p.job_id, j.status,
    j.attempts, j.last_error, j.wall_seconds, j.start_mode,
    NULL, r.phase, r.wall_seconds, r.trend, r.verdict))
FROM sweep_points p
JOIN jobs j INDEXED BY jobs_report ON j.id = p.job_id
LEFT JOIN results r INDEXED BY results_report ON r.job_id = p.job_id
WHERE p.sweep_id = ?1
