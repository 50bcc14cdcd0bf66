-- Marks a new file as wetgran's (APPLICATION_ID, "WGRN"); a PRAGMA takes no bound parameter.
-- no parameters
PRAGMA application_id = 1464291918
