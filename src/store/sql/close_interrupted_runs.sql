-- Closes the open run rows of a runner whose process is gone, as interrupted.
-- ?1: owner, ?2: now
UPDATE runs SET outcome = 'interrupted', ended_at = ?2
WHERE owner = ?1 AND outcome IS NULL
