-- Copies a job row under its new id (re-keying).
-- ?1: old job id, ?2: new job id
INSERT INTO jobs (id, spec, status, attempts, owner, heartbeat,
    claimed_at, finished_at, wall_seconds, last_error, created_at, start_from, start_mode)
SELECT ?2, spec, status, attempts, owner, heartbeat, claimed_at,
    finished_at, wall_seconds, last_error, created_at, start_from, start_mode
FROM jobs WHERE id = ?1
