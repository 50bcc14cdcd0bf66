-- A job's checkpoint state (JSON).
-- ?1: job id
SELECT state FROM checkpoints WHERE job_id = ?1
