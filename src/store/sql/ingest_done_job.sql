-- Marks a job done with a result computed elsewhere, unless it already has a result.
-- ?1: job id, ?2: owner, ?3: finished at, ?4: wall seconds
UPDATE jobs SET status = 'done', owner = ?2, heartbeat = NULL, finished_at = ?3,
    wall_seconds = ?4, last_error = NULL, attempts = attempts + 1
WHERE id = ?1 AND NOT EXISTS (SELECT 1 FROM results WHERE job_id = ?1)
