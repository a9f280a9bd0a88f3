"""A plant of cells: each cell publishes its calibration health to the plant's MQTT broker; the fleet
view (``handeye plant``) subscribes, keeps the history and shows one row per cell.

Cell side: ``settings`` (the station file's ``plant:`` section), ``events`` (what is published),
``outbox`` (events kept until the broker acknowledged them), ``client`` (paho-mqtt, TLS, credentials),
``publisher`` (sending in order, QoS 1, the retained state), ``hooks`` (the one call each command makes).
Fleet side: ``fleet_config`` (plant.yaml), ``store`` (SQLite history, each event once, in order),
``subscriber``, ``fleet`` (the table and its alarms), ``view`` (the page, on the live view's server).

Importing this package imports nothing of MQTT: paho is imported only when a ``plant:`` section is used.
"""
