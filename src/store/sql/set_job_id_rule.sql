-- Records the rule the job ids follow (meta key `job_ids`).
-- ?1: the rule (JOB_ID_RULE)
INSERT OR REPLACE INTO meta (key, value) VALUES ('job_ids', ?1)
