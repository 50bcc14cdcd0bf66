-- A finished job extended from its checkpoint: new finish time, wall time added.
-- ?1: job id, ?2: finished at, ?3: wall seconds added
UPDATE jobs SET finished_at = ?2, wall_seconds = coalesce(wall_seconds, 0) + ?3
WHERE id = ?1
