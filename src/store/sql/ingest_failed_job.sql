-- Marks a job failed elsewhere, unless it is done or running.
-- ?1: job id, ?2: owner, ?3: finished at, ?4: wall seconds, ?5: error message
UPDATE jobs SET status = 'failed', owner = ?2, heartbeat = NULL,
    finished_at = ?3, wall_seconds = ?4, last_error = ?5, attempts = attempts + 1
WHERE id = ?1 AND status IN ('pending', 'failed')
