-- Puts a sweep's failed jobs back to pending.
-- ?1: sweep id
UPDATE jobs SET status = 'pending', owner = NULL, heartbeat = NULL
WHERE status = 'failed'
  AND id IN (SELECT job_id FROM sweep_points WHERE sweep_id = ?1)
