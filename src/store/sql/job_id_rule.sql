-- The rule the job ids of this database follow (meta key `job_ids`).
-- no parameters
SELECT value FROM meta WHERE key = 'job_ids'
