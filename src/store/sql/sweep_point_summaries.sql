-- Every job of a sweep (grid order) with what the reports (`sweep status`, `boundaries`,
-- `plot`) read of it: indexed scalar columns, no observables JSON, and of the spec only its
-- start mode (NULL: the default, hot) and, where asked, the whole spec (for sweeps
-- whose axes may change what the reports read of a scene: `Store::point_summaries`). The
-- columns come from covering indexes (migrations 20261127150000, 20261202000000), not from the rows that hold
-- the observables.
-- `job_wall_seconds` is the job's last ended attempt (`time_spent.sql` sums it).
-- ?1: sweep id, ?2: whether to return every job's spec (1) or none (0)
SELECT p.point, p.replica, p.coords, p.job_id, j.status, j.attempts, j.last_error,
    j.wall_seconds AS job_wall_seconds,
    j.start_mode AS start,
    CASE WHEN ?2 THEN j.spec END AS spec,
    r.phase, r.wall_seconds, r.trend, r.verdict
FROM sweep_points p
JOIN jobs j INDEXED BY jobs_report ON j.id = p.job_id
LEFT JOIN results r INDEXED BY results_report ON r.job_id = p.job_id
WHERE p.sweep_id = ?1
ORDER BY p.point, p.replica
