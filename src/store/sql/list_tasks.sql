-- Every recorded task of a sweep, oldest submission first.
-- ?1: sweep id
SELECT s.id AS submission_id, s.sweep_id, s.dir, s.slurm_job, t.task, t.job_id, t.state,
    t.message, s.submitted_at
FROM submission_tasks t
JOIN submissions s ON s.id = t.submission_id
WHERE s.sweep_id = ?1
ORDER BY s.id, t.task
