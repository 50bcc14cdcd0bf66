-- Deletes a job's result.
-- ?1: job id
DELETE FROM results WHERE job_id = ?1
