-- Every running job with its owner and heartbeat.
-- no parameters
SELECT id, owner, heartbeat FROM jobs WHERE status = 'running'
