-- Closes an orphaned job's open run rows.
-- ?1: job id, ?2: owner, ?3: now
UPDATE runs SET outcome = 'orphaned', ended_at = ?3
WHERE job_id = ?1 AND owner = ?2 AND outcome IS NULL
