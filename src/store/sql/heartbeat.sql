-- Refreshes the heartbeat of a runner's running jobs.
-- ?1: now, ?2: owner
UPDATE jobs SET heartbeat = ?1 WHERE owner = ?2 AND status = 'running'
