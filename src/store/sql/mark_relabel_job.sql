-- Marks a job's result as not yet relabelled by the line rule, in every sweep that holds the job
-- (meta keys `relabel:<sweep id>:<job id>`; `run::relabel::relabel_changed` reads and clears
-- them). Written in the transaction that stores or replaces the result.
-- ?1: job id
INSERT OR IGNORE INTO meta (key, value)
SELECT 'relabel:' || sweep_id || ':' || job_id, '' FROM sweep_points WHERE job_id = ?1
