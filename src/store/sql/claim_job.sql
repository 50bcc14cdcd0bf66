-- Claims a pending job for a runner (inside the claim's write transaction); returns its spec,
-- no row if the job is not pending.
-- ?1: job id, ?2: owner, ?3: now
UPDATE jobs SET status = 'running', owner = ?2, heartbeat = ?3, claimed_at = ?3,
    attempts = attempts + 1
WHERE id = ?1 AND status = 'pending'
RETURNING spec
