"""The scene: what the skin touches and how it is built.

- :mod:`mjtouch.scene.scenes`    MJCF builders on ``mujoco.MjSpec`` (fingertip,
  plates, sliding scenes) and their parameters (``Fingertip``, ``Protocol``)
- :mod:`mjtouch.scene.textures`  ``Texture`` and the height-map generators
- :mod:`mjtouch.scene.meshes`    textures from mesh files (``from_mesh``)
- :mod:`mjtouch.scene.sensor`    ``SkinLayout``: reading the plugin's sensordata
- :mod:`mjtouch.scene.robot`     ``attach`` a skin to any robot's fingertip geom
"""
