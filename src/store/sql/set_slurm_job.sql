-- Adds the Slurm job id to a submission.
-- ?1: submission id, ?2: Slurm job id
UPDATE submissions SET slurm_job = ?2 WHERE id = ?1
