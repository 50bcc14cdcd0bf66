-- Moves a result to the merged job, unless that job already has one (re-keying).
-- ?1: old job id, ?2: new job id
UPDATE results SET job_id = ?2 WHERE job_id = ?1
AND NOT EXISTS (SELECT 1 FROM results WHERE job_id = ?2)
