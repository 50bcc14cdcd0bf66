-- Total wall time of a sweep's finished and failed jobs (from the covering index `jobs_report`,
-- not from the job rows with their specs).
-- ?1: sweep id
SELECT sum(j.wall_seconds) FROM jobs j INDEXED BY jobs_report
WHERE j.id IN (SELECT job_id FROM sweep_points WHERE sweep_id = ?1)
  AND j.status IN ('done', 'failed')
