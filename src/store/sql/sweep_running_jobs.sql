-- The running jobs of a sweep with their runner and its last heartbeat (`sweep status` tells
-- live runners from stale ones): the few running jobs, each looked up in the sweep's points.
-- ?1: sweep id
SELECT p.point, p.replica, j.id AS job_id, j.owner, j.heartbeat
FROM jobs j INDEXED BY jobs_status
JOIN sweep_points p ON p.job_id = j.id
WHERE j.status = 'running' AND p.sweep_id = ?1
