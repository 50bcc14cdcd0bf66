-- Marks a job this runner is running failed.
-- ?1: job id, ?2: owner, ?3: finished at, ?4: wall seconds, ?5: error message
UPDATE jobs SET status = 'failed', heartbeat = NULL, finished_at = ?3,
    wall_seconds = ?4, last_error = ?5
WHERE id = ?1 AND owner = ?2 AND status = 'running'
