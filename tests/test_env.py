"""PixelWorldEnv: Gymnasium/SB3 compliance, exact rewards, movement, pushing, observations, rendering."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

from pixelworld_env import Color, PixelWorldEnv, Scene
from pixelworld_env.core.constants import NUM_COLORS
from pixelworld_env.core.render import HUMAN_CELL_SIZE, rgb_image
from tests.helpers import CONTAINER, IN_CONTAINER, classification_env, import_tool, make

DOWN, RIGHT, UP, LEFT = "DOWN", "RIGHT", "UP", "LEFT"

def act(env: PixelWorldEnv, name: str):
    return env.step(env.action_names.index(name))


def test_action_names_follow_the_paper() -> None:
    assert classification_env().action_names == ("SIG0", "SIG1", "DOWN", "RIGHT", "UP", "LEFT")
    assert make().action_names == ("SIG1", "DOWN", "RIGHT", "UP", "LEFT")
    assert make().action_space == gym.spaces.Discrete(5)


@pytest.mark.parametrize("observation", ["hand", "hand_raw"])
@pytest.mark.parametrize("kind", ["classification", "bring-about"])
def test_gymnasium_and_sb3_check_env_without_warnings(kind: str, observation: str) -> None:
    env = classification_env(observation=observation) if kind == "classification" else make(
        observation=observation)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gym_check_env(env, skip_render_check=True)
        sb3_check_env(env, warn=True)


def test_labels_default_to_the_concept() -> None:
    env = classification_env()
    assert env.labels == (1, 0)
    with pytest.raises(ValueError, match="got 1 labels for 2 scenes"):
        PixelWorldEnv(env.scenes, kind="classification", concept=IN_CONTAINER, labels=[1])


@pytest.mark.parametrize(("index", "action", "reward"), [(0, "SIG1", 1.0), (0, "SIG0", -1.0), (1, "SIG0", 1.0),
                                                         (1, "SIG1", -1.0)])
def test_classification_rewards(index: int, action: str, reward: float) -> None:
    env = classification_env()
    env.reset(seed=0, options={"index": index})
    assert act(env, DOWN)[1:4] == (0.0, False, False)
    obs, r, terminated, truncated, info = act(env, action)
    assert (r, terminated, truncated) == (reward, True, False)
    assert info["is_success"] is (reward > 0) and info["label"] == (1 - index) and info["signalled"]
    with pytest.raises(RuntimeError, match="call reset"):
        act(env, DOWN)


def test_bring_about_shaping_sequence() -> None:
    env = make()
    _, info = env.reset(seed=0)
    assert info == {"scene_index": 0, "is_success": False, "signalled": False, "goal": False}
    rewards = []
    for name in [DOWN, DOWN, UP, DOWN, RIGHT, LEFT, "SIG1"]:
        _, r, terminated, truncated, info = act(env, name)
        rewards.append(r)
        assert "is_success" in info and "goal" in info
    # (1,4) -> (2,4) inside -> (3,4) supported: +0.5; up: -0.5; down: +0.5; right stays supported; SIG1: +0.5
    assert rewards == [0.0, 0.5, -0.5, 0.5, 0.0, 0.0, 0.5]
    assert terminated and not truncated and info["is_success"] and info["goal"]


def test_bring_about_signal_outside_goal_and_time_limit() -> None:
    env = make()
    env.reset(seed=0)
    _, r, terminated, _, info = act(env, "SIG1")
    assert (r, terminated, info["is_success"]) == (0.0, True, False)
    env = make(max_steps=3)
    env.reset(seed=0)
    act(env, DOWN)
    act(env, LEFT)
    _, r, terminated, truncated, info = act(env, RIGHT)
    assert (r, terminated, truncated, info["is_success"]) == (0.0, False, True, False)
    # entering the goal on the very last step counts as a success under the paper's rule
    env = make(max_steps=2)
    env.reset(seed=0)
    act(env, DOWN)
    _, r, terminated, truncated, info = act(env, DOWN)
    assert (r, terminated, truncated, info["is_success"], info["signalled"]) == (0.5, False, True, True, False)


def test_blocked_moves_cost_a_step_and_change_nothing() -> None:
    env = make(max_steps=5)
    obs, _ = env.reset(seed=0)
    act(env, DOWN)
    act(env, DOWN)  # now on the container floor at (3, 4)
    before = env.world.state().copy()
    obs, r, _, _, _ = act(env, DOWN)  # container floor below
    assert r == 0.0 and env.world.self_position == (3, 4)
    np.testing.assert_array_equal(env.world.state(), before)
    act(env, UP)
    _, _, _, truncated, _ = act(env, UP)
    assert truncated  # five actions, blocked one included


def test_hand_window_at_frame_and_floor() -> None:
    text = """
    #######
    #S....#
    #.....#
    #.a...#
    #=====#
    #.....#
    #######
    """
    env = PixelWorldEnv([Scene.from_ascii(text)], kind="bring-about", concept="?x blob(x) & touches(self,x)",
                        observation="hand_raw")
    obs, _ = env.reset(seed=0)
    assert obs.tolist() == [7, 7, 7, 7, 2, 0, 7, 0, 0]
    obs, r, *_ = act(env, DOWN)  # (2, 1) touches the blob at (3, 2) diagonally
    assert obs.tolist() == [7, 0, 0, 7, 2, 0, 7, 0, 1] and r == 0.5
    obs, r, *_ = act(env, DOWN)
    assert obs.tolist() == [7, 0, 0, 7, 2, 1, 7, 3, 3] and r == 0.0
    obs, r, *_ = act(env, RIGHT)  # blocked by the blob
    assert obs.tolist() == [7, 0, 0, 7, 2, 1, 7, 3, 3] and r == 0.0 and env.world.self_position == (3, 1)
    onehot = PixelWorldEnv([Scene.from_ascii(text)], kind="bring-about", concept="?x blob(x)").reset(seed=0)[0]
    assert onehot.shape == (81,) and onehot.dtype == np.float32
    np.testing.assert_array_equal(onehot.reshape(9, 9).argmax(axis=1), [7, 7, 7, 7, 2, 0, 7, 0, 0])
    assert onehot.sum() == 9


PUSH = """
##########
#........#
#.SAB.c..#
#........#
##########
"""


def test_pushing_moves_chains_and_is_blocked_by_immoveables() -> None:
    scene = Scene.from_ascii(PUSH)
    env = PixelWorldEnv([scene], kind="bring-about", concept="?x ?y touches(x,y) & blob(x) & blob(y)")
    env.reset(seed=0)
    assert env.world.self_only is False
    act(env, RIGHT)  # S pushes A which pushes B: B now touches c (drawn as "a" by to_ascii)
    state = env.world.current_scene().to_ascii().splitlines()
    assert state[2] == "#..SABa..#"
    act(env, RIGHT)  # c is immoveable: the whole chain is blocked
    assert env.world.current_scene().to_ascii().splitlines()[2] == "#..SABa..#"
    act(env, UP)
    act(env, RIGHT)
    act(env, RIGHT)
    act(env, DOWN)  # from above B: pushing down moves B alone
    lines = env.world.current_scene().to_ascii().splitlines()
    assert lines[2] == "#...ASa..#" and lines[3] == "#....B...#"
    act(env, DOWN)  # B would enter the frame: blocked
    assert env.world.current_scene().to_ascii().splitlines()[3] == "#....B...#"
    env.reset(seed=0)  # reset restores the initial positions
    assert env.world.current_scene() == scene


def test_pushing_shapes_rigidly_and_goal_after_push() -> None:
    text = """
    ##########
    #........#
    #.S.AA...#
    #...A....#
    #......b.#
    ##########
    """
    scene = Scene.from_ascii(text, {"b": "small_blob"})
    env = PixelWorldEnv([scene], kind="bring-about", concept="?x ?y blob(x) & small_blob(y) & touches(x,y)")
    env.reset(seed=0)
    rewards = [act(env, RIGHT)[1] for _ in range(3)]
    lines = env.world.current_scene().to_ascii().splitlines()
    assert lines[2] == "#....SAA.#" and lines[3] == "#.....A..#"
    assert rewards == [0.0, 0.0, 0.5]  # the pushed blob touches b diagonally after the third push


def test_same_seed_same_rollout_and_reset_index() -> None:
    def rollout(seed: int) -> list:
        env = classification_env()
        env.action_space.seed(seed)
        out = []
        obs, info = env.reset(seed=seed)
        for _ in range(200):
            obs, r, term, trunc, info = env.step(env.action_space.sample())
            out.append((obs.tobytes(), r, term, trunc, info["scene_index"]))
            if term or trunc:
                obs, info = env.reset()
        return out

    assert rollout(3) == rollout(3)
    assert rollout(3) != rollout(4)
    env = classification_env()
    assert env.reset(seed=0, options={"index": 1})[1]["scene_index"] == 1
    with pytest.raises(IndexError, match="scene index 2 out of range"):
        env.reset(options={"index": 2})


def test_pickle_round_trip_mid_episode() -> None:
    env = make()
    env.reset(seed=5)
    act(env, DOWN)
    clone = pickle.loads(pickle.dumps(env))
    for name in [DOWN, RIGHT, "SIG1"]:
        a, b = act(env, name), act(clone, name)
        np.testing.assert_array_equal(a[0], b[0])
        assert a[1:] == b[1:]


def test_aaai18_reset_bug_leaves_a_stale_self_pixel() -> None:
    fixed = make(observation="hand_raw")
    buggy = make(observation="hand_raw", aaai18_reset_bug=True)
    for env in (fixed, buggy):
        env.reset(seed=0)
        act(env, RIGHT)  # end the episode at (1, 5), next to the start (1, 4)
        act(env, "SIG1")
    assert fixed.reset(seed=0)[0].tolist() == [7, 7, 7, 0, 2, 0, 0, 0, 0]
    obs, _ = buggy.reset(seed=0)
    assert obs.tolist() == [7, 7, 7, 0, 2, 2, 0, 0, 0]  # the stale red pixel at (1, 5)
    obs, *_ = act(buggy, UP)  # blocked by the frame: the stale pixel stays
    assert obs.tolist() == [7, 7, 7, 0, 2, 2, 0, 0, 0]
    obs, *_ = act(buggy, LEFT)  # a successful move redraws the world: (1, 3) sees the container at (2, 2)
    assert obs.tolist() == [7, 7, 7, 0, 2, 0, 1, 0, 0]
    assert buggy.world.state()[1, 5] == Color.EMPTY


def test_render_modes() -> None:
    env = make(render_mode="rgb_array")
    env.reset(seed=0)
    image = env.render()
    assert image.shape == (80, 90, 3) and image.dtype == np.uint8
    assert tuple(image[15, 45]) == (220, 30, 30)  # the self is red
    assert tuple(image[55, 15]) != tuple(image[5, 5])  # floor and frame differ
    text = make(render_mode="ansi")
    text.reset(seed=0)
    assert text.render() == Scene.from_ascii(CONTAINER, {"a": "container"}).to_ascii() + "\n"
    with pytest.raises(ValueError, match=r"render_mode must be None or one of \['human', 'rgb_array', 'ansi'\]"):
        make(render_mode="window")


def test_human_rendering_without_pygame_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "pygame", None)  # what an install without pygame sees
    with pytest.raises(gym.error.DependencyNotInstalled,
                       match=r'pygame is not installed: pip install "sb3-smc\[render\]"'):
        make(render_mode="human")


@pytest.fixture
def pygame_display(monkeypatch: pytest.MonkeyPatch):
    """pygame with its display shut (each test starts its own), no display variable and no chosen video driver."""
    pygame = pytest.importorskip("pygame", reason="pygame is in the [test] extra")
    for name in ("DISPLAY", "WAYLAND_DISPLAY", "SDL_VIDEODRIVER"):
        monkeypatch.delenv(name, raising=False)
    pygame.display.quit()
    yield pygame
    pygame.display.quit()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="DISPLAY / WAYLAND_DISPLAY are Linux's displays")
def test_human_rendering_on_a_machine_without_a_display_draws_off_screen_and_says_so(pygame_display) -> None:
    with pytest.warns(UserWarning, match=r'render_mode="human": pygame finds no display here \(video driver: '
                                         r"(offscreen|dummy); DISPLAY=None, WAYLAND_DISPLAY=None\), so the window is "
                                         r"drawn off screen and nothing is shown; set SDL_VIDEODRIVER=dummy"):
        env = make(render_mode="human")
    env.reset(seed=0)
    shown = pygame_display.surfarray.array3d(pygame_display.display.get_surface()).swapaxes(0, 1)
    np.testing.assert_array_equal(shown, rgb_image(env.world.state(), HUMAN_CELL_SIZE, env.world.self_position))
    env.close()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="DISPLAY / WAYLAND_DISPLAY are Linux's displays")
def test_human_rendering_without_a_display_prints_only_its_own_warning(tmp_path) -> None:
    """No SDL probe of Wayland / X11 first (its "XDG_RUNTIME_DIR is invalid" line), and the driver is chosen for
    the call only: the process's environment is left as it was."""
    pytest.importorskip("pygame", reason="pygame is in the [test] extra")
    code = ("import os, gymnasium as gym, pixelworld_env; "
            "env = gym.make('PW-cl_self-in-left-corner_vs_on-hline-v0', render_mode='human'); env.reset(seed=0); "
            "env.step(2); env.close(); env.reset(seed=1); env.render(); env.close(); "
            "print(os.environ.get('SDL_VIDEODRIVER'))")
    environment = {k: v for k, v in os.environ.items()
                   if k not in ("DISPLAY", "WAYLAND_DISPLAY", "SDL_VIDEODRIVER", "XDG_RUNTIME_DIR")}
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=environment,
                            cwd=tmp_path, check=True)
    assert result.stdout.strip() == "None" and "XDG_RUNTIME_DIR" not in result.stderr
    assert result.stderr.count("UserWarning") == 1
    assert 'WARN: render_mode="human": pygame finds no display' in result.stderr


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="DISPLAY / WAYLAND_DISPLAY are Linux's displays")
def test_human_rendering_with_a_video_driver_that_cannot_start_says_so(pygame_display,
                                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SDL_VIDEODRIVER", "x11")  # chosen on purpose, and no X display
    with pytest.raises(RuntimeError, match=r'render_mode="human" draws in a pygame window, and pygame has no video '
                                           r"driver here \(.*; SDL_VIDEODRIVER='x11', DISPLAY=None, "
                                           r"WAYLAND_DISPLAY=None\): run it where a screen is attached"):
        make(render_mode="human")
    assert not pygame_display.display.get_init()


def test_gymnasium_check_env_passes_every_render_mode_without_a_display() -> None:
    """``check_env`` builds the env in every mode of ``metadata["render_modes"]``, "human" included: without a
    display (and without SDL_VIDEODRIVER) that mode draws off screen and warns, as Gymnasium's own envs pass."""
    pytest.importorskip("pygame", reason="pygame is in the [test] extra")
    code = ("import gymnasium as gym, pixelworld_env\n"
            "from gymnasium.utils.env_checker import check_env\n"
            "for env_id in ('PW-ba_self-in-container-v0', 'PW-cl_self-in-container_vs_noncontainer-v0'):\n"
            "    check_env(gym.make(env_id).unwrapped)\n"
            "print('passed')\n")
    headless = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "SDL_VIDEODRIVER")}
    result = subprocess.run([sys.executable, "-c", code], env=headless, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0 and result.stdout.splitlines()[-1] == "passed", result.stderr
    assert "so the window is drawn off screen and nothing is shown" in result.stderr


def test_human_window_shows_the_rgb_frame_on_reset_and_step(pygame_display, monkeypatch: pytest.MonkeyPatch) -> None:
    """SDL's dummy driver, chosen on purpose, draws the window's frames without a screen."""
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    env = make(render_mode="human")
    rgb = make(render_mode="rgb_array")

    def shown() -> np.ndarray:
        return pygame_display.surfarray.array3d(pygame_display.display.get_surface()).swapaxes(0, 1)

    env.reset(seed=0)
    expected = rgb_image(env.world.state(), cell_size=HUMAN_CELL_SIZE, window=env.world.self_position)
    assert expected.shape == (8 * HUMAN_CELL_SIZE, 9 * HUMAN_CELL_SIZE, 3)
    np.testing.assert_array_equal(shown(), expected)
    rgb.reset(seed=0)
    np.testing.assert_array_equal(rgb.render(), rgb_image(env.world.state(), window=env.world.self_position))
    assert env.step(env.action_names.index(DOWN))[1:] == rgb.step(rgb.action_names.index(DOWN))[1:]
    np.testing.assert_array_equal(shown(), rgb_image(env.world.state(), HUMAN_CELL_SIZE, env.world.self_position))
    assert env.render() is None and pygame_display.display.get_caption()[0] == f"PixelWorld: {IN_CONTAINER}"
    env.close()
    assert not pygame_display.display.get_init()


def test_image_observation_is_the_channel_first_one_hot_grid() -> None:
    env = gym.make("PW-cl_self-in-container_vs_noncontainer-v0", observation="image")
    obs, _ = env.reset(seed=0)
    assert env.observation_space == gym.spaces.Box(0, 255, (NUM_COLORS, 18, 35), np.uint8)
    state = env.unwrapped.world.state()
    np.testing.assert_array_equal(obs, (np.arange(NUM_COLORS)[:, None, None] == state) * 255)
    obs, *_ = env.step(env.unwrapped.action_names.index(DOWN))
    assert env.observation_space.contains(obs) and obs.sum(axis=0).tolist() == np.full((18, 35), 255).tolist()
    np.testing.assert_array_equal(obs.argmax(axis=0), env.unwrapped.world.state())
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gym_check_env(env.unwrapped, skip_render_check=True)
    with pytest.raises(ValueError, match="observation='image' needs scenes of at least 9 x 9 cells, got 8 x 9"):
        make(observation="image")


def test_full_observation() -> None:
    env = make(observation="full")
    obs, _ = env.reset(seed=0)
    assert obs.shape == (8, 9) and obs.dtype == np.uint8
    assert env.observation_space.contains(obs)
    assert obs[1, 4] == Color.RED and obs[5, 1] == Color.BLUE and obs[0, 0] == Color.PURPLE


def test_goal_memo_matches_direct_evaluation() -> None:
    env = make()
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    for _ in range(300):
        _, _, term, trunc, info = env.step(int(rng.integers(1, 5)))
        assert info["goal"] == env.concept.holds(env.world.current_scene())
        if term or trunc:
            env.reset()


def test_oracle_plans_with_and_without_pushing() -> None:
    from pixelworld_env.generation.oracle import plan_to_goal

    env = make()
    env.reset(seed=0)
    plan = plan_to_goal(env)
    assert [env.action_names[a] for a in plan] == [DOWN, DOWN]
    text = """
    ##########
    #........#
    #.S.A....#
    #........#
    #......b.#
    ##########
    """
    push = PixelWorldEnv([Scene.from_ascii(text, {"b": "small_blob"})], kind="bring-about",
                         concept="?x ?y blob(x) & small_blob(y) & touches(x,y)")
    push.reset(seed=0)
    plan = plan_to_goal(push)
    assert len(plan) == 6  # step to A, push it right twice, go round it, push it down once
    rewards = [push.step(a)[1] for a in plan]
    assert rewards[-1] == 0.5 and push.goal_holds()
    walled = PixelWorldEnv([Scene.from_ascii("######\n#Sb.a#\n######", {"b": "hline", "a": "small_blob"})],
                           kind="bring-about", concept="?x small_blob(x) & touches(self,x)")
    walled.reset(seed=0)
    assert plan_to_goal(walled) is None


@pytest.mark.parametrize("env_id", ["PW-cl_self-in-container_vs_noncontainer-v0",
                                    "PW-ba_self-in-container_from_between-potential-containers-v0"])
def test_hand_observation_is_the_one_hot_window_after_any_moves(env_id: str) -> None:
    env = gym.make(env_id, observation="hand", disable_env_checker=True).unwrapped
    rng = np.random.default_rng(0)
    for episode in range(6):
        env.reset(seed=episode)
        for _ in range(40):  # moves only (each memoised window is checked against a fresh one)
            env.apply_move(int(rng.integers(env.action_names.index("DOWN"), env.action_names.index("LEFT") + 1)))
            expected = np.zeros((9, 9), dtype=np.float32)
            expected[np.arange(9), env.world.window().ravel()] = 1.0
            np.testing.assert_array_equal(env.hand_observation(), expected.reshape(-1))
            out = np.zeros(90, dtype=np.float32)
            assert env.hand_observation(out=out) is out and np.array_equal(out[:81], expected.reshape(-1))


def test_the_fewest_moves_to_a_goal_cell_by_breadth_first_search(capsys):
    """``tools/probe_paths.py``: the fewest moves from the self to where the concept holds (the package's planner),
    around a container's wall (5 here: four right over the wall, one down into it), ``None`` when an object shuts the
    goal off, and a classification dataset refused before any work."""
    probe_paths = import_tool("probe_paths")
    concept = "?x container(x) & inside_supported(self,x)"

    def env_of(grid: str) -> PixelWorldEnv:
        env = PixelWorldEnv([Scene.from_ascii(grid, kinds={"a": "container"})], kind="bring-about", concept=concept)
        env.reset(seed=0)
        return env

    open_world = env_of("###########\n#.........#\n#..S......#\n#.....a..a#\n#.....aaaa#\n#=========#\n###########")
    assert probe_paths.fewest_moves(open_world) == 5
    shut = env_of("###########\n#.....bbbb#\n#..S..b...#\n#.....ba.a#\n#.....baaa#\n#=========#\n###########")
    assert probe_paths.fewest_moves(shut) is None
    with pytest.raises(SystemExit):
        probe_paths.main(["cl_self-in-container_vs_noncontainer"])
    assert "only bring-about datasets have goal cells" in capsys.readouterr().err
