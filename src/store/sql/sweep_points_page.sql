-- A page of a sweep's jobs (grid order) with their results, those after a given grid point
-- and replica: `export` reads a sweep a page at a time, so its memory does not grow with the
-- sweep (a keyset page: a range of the primary key, not an OFFSET that re-reads every row before
-- it).
-- ?1: sweep id, ?2: point of the last row read (-1 before the first page), ?3: its replica
-- (-1 before the first page), ?4: rows per page
SELECT p.point, p.replica, p.coords, p.job_id, j.status, j.spec, j.attempts,
    j.last_error, r.phase, r.decided_on, r.observables, r.simulated_time,
    r.wall_seconds, r.events, r.finished_at, r.owner AS result_owner, r.trend
FROM sweep_points p
JOIN jobs j ON j.id = p.job_id
LEFT JOIN results r ON r.job_id = p.job_id
WHERE p.sweep_id = ?1 AND (p.point, p.replica) > (?2, ?3)
ORDER BY p.point, p.replica
LIMIT ?4
