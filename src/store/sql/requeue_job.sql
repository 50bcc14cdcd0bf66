-- Puts an orphaned running job back to pending (if it is still that owner's).
-- ?1: job id, ?2: owner
UPDATE jobs SET status = 'pending', owner = NULL, heartbeat = NULL
WHERE id = ?1 AND status = 'running' AND owner = ?2
