# ArmLab Control Station on the MuJoCo simulation, rendering offscreen on the CPU through EGL.
FROM python:3.11-slim
RUN apt-get update \
 && apt-get install -y --no-install-recommends libegl1 libgles2 libgl1 libosmesa6 nodejs npm \
 && rm -rf /var/lib/apt/lists/*
ENV MUJOCO_GL=egl PYTHONUNBUFFERED=1
WORKDIR /app
COPY . /app
RUN pip install --no-cache-dir -e . \
 && if [ -f web/package.json ]; then cd web && npm ci --no-audit --no-fund; fi
EXPOSE 8000
CMD ["armlab", "serve", "--host", "0.0.0.0"]
